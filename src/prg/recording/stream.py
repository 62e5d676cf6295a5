"""The recording stream: an explicit :class:`rerun.RecordingStream` saving to a file, atomically.

Every recording goes through :func:`recording_stream` (never Rerun's global recording), which
writes to a temporary name in the destination folder and renames it into place only when the
``with`` block ends cleanly: a reader never sees half a file, and an error leaves nothing behind.
"""

from __future__ import annotations

import errno
import logging
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import rerun as rr
import rerun.blueprint as rrb

from prg.errors import UsageError
from prg.files import atomic_path

log = logging.getLogger("prg.recording")

FLUSH_TIMEOUT_S = 60.0  # seconds a recording may take to reach its file at the end


@contextmanager
def recording_stream(
    path: str | os.PathLike,
    application_id: str,
    *,
    recording_id: str | None = None,
    blueprint: rrb.BlueprintLike | None = None,
) -> Iterator[rr.RecordingStream]:
    """A recording stream saving to ``path``, atomically.

    The stream writes to a temporary file next to ``path``; on a clean exit it is flushed,
    closed and renamed to ``path`` (replacing any file there). If the block raises, the
    temporary file is removed, ``path`` is left as it was, and the exception propagates.

    Parameters
    ----------
    path : path-like
        The ``.rrd`` file to write; its folder is created if missing.
    application_id : str
        Rerun application id (recordings of one application share blueprints in the viewer).
    recording_id : str, optional
        Fixed recording id (default: a random one).
    blueprint : rerun.blueprint.BlueprintLike, optional
        Default blueprint stored in the file.

    Yields
    ------
    rerun.RecordingStream
        An explicit stream (not made the global or thread-local default).

    Raises
    ------
    UsageError
        If the file cannot be created (one line naming ``path``).
    """
    path = Path(path)
    rec = rr.RecordingStream(application_id, recording_id=recording_id)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise UsageError(f"{path}: cannot write the recording ({err})") from None
    with atomic_path(path) as tmp:
        try:
            rec.save(tmp, default_blueprint=blueprint)
        except (OSError, RuntimeError) as err:
            raise UsageError(f"{path}: cannot write the recording ({err})") from None
        try:
            yield rec
            try:
                # finite: after a failed write, rerun's flush can wait for its dead writer thread
                # for ever (seen under a file-size limit); a word's recording flushes in < 1 s
                rec.flush(timeout_sec=FLUSH_TIMEOUT_S)
            except (RuntimeError, TimeoutError) as err:  # the file writer failed (a full disk)
                raise OSError(
                    errno.EIO, f"the recording could not be written ({err})", tmp
                ) from err
        finally:
            rec.disconnect()  # closes the file before it is renamed or removed
    log.debug("wrote recording %s", path)
