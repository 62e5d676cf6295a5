"""Files: writes that are all or nothing (a file or a folder appears complete, or not at all),
JSON text and file hashes.

Every output of the project goes through here. A file is written under a hidden temporary name
beside its final name and renamed over it (``os.replace`` is atomic within a file system); a
folder of outputs is built in a hidden staging folder and moved into place at the end. When the
write fails halfway (a full disk, a bug, a signal), the temporary file or folder is removed and
the previous output is left as it was.

Temporary names carry the writer's process id (``.NAME.tmp-PID``, ``.NAME.old-PID``), so a later
run can tell the leftovers of a process that was killed outright (``SIGKILL``, power loss) from a
write in progress and remove them: :func:`remove_stale` runs before every staged write.

An :class:`OSError` raised while writing names the final path, not the temporary one (a full disk
raises ``ENOSPC`` with no file name at all), so the one-line error tells the user which output
could not be written.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import os
import re
import shutil
import string
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Any

import numpy as np

from prg.errors import UsageError
from prg.signals import deferred

_LEFTOVER = re.compile(r"^\..+\.(?:tmp|old)-(\d+)(?:\.\w+)?$")


def _temp_name(path: Path, kind: str = "tmp") -> Path:
    return path.with_name(f".{path.name}.{kind}-{os.getpid()}")


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by another user
        return True
    return True


def remove_stale(folder: str | os.PathLike) -> list[Path]:
    """Remove the temporary files and folders that killed writers left in ``folder``.

    Only hidden entries named like this module's temporary names whose process no longer runs
    are removed (this process's own are kept). Returns what was removed.
    """
    folder = Path(folder)
    removed: list[Path] = []
    if not folder.is_dir():
        return removed
    for entry in folder.iterdir():
        match = _LEFTOVER.match(entry.name)
        if not match or int(match[1]) == os.getpid() or _pid_alive(int(match[1])):
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry, ignore_errors=True)
        else:
            entry.unlink(missing_ok=True)
        removed.append(entry)
    return removed


def _raise_naming_final(err: OSError, tmp: Path, final: Path) -> None:
    """Raise ``err`` naming the user's path: ``final`` (or the path below it) where it named the
    temporary path (or a path below it) or no path at all (ENOSPC names none)."""
    if err.filename is None:
        name = final
    else:
        try:
            name = final / Path(os.fsdecode(err.filename)).relative_to(tmp)
        except ValueError:
            raise err from err.__cause__  # about another file: as it is
    raise OSError(err.errno, err.strerror or str(err), str(name)) from err


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)


@contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; when the block ends normally it is renamed to
    ``path``, otherwise removed (``path`` keeps its old content).

    For writers that want a file name (``np.savez``, ``trainer.save_checkpoint``, PIL, matplotlib);
    the temporary name keeps ``path``'s suffix so such writers pick the right format. The
    folder is created if missing.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.tmp-{os.getpid()}{path.suffix}")
    try:
        yield tmp
        os.replace(tmp, path)
    except OSError as err:
        _raise_naming_final(err, tmp, path)
    finally:
        _remove(tmp)


def move_into_place(tmp: str | os.PathLike, path: str | os.PathLike) -> Path:
    """Rename the finished temporary file ``tmp`` (written beside ``path``) over ``path``: atomic
    within a file system. An :class:`OSError` names ``path``, not ``tmp``; ``tmp`` is then left
    for the caller to remove. Returns ``path``.

    For writers that make their own temporary file (a download that streams and verifies it);
    other writers use :func:`atomic_path`.
    """
    tmp, path = Path(tmp), Path(path)
    try:
        os.replace(tmp, path)
    except OSError as err:
        _raise_naming_final(err, tmp, path)
    return path


def write_bytes(path: str | os.PathLike, data: bytes, *, atomic: bool = True) -> Path:
    """Write ``data`` to ``path`` atomically (``atomic=False``: in place, for a path that is
    already a temporary name, e.g. from :func:`atomic_path`)."""
    path = Path(path)
    if atomic:
        with atomic_path(path) as tmp:
            write_bytes(tmp, data, atomic=False)
        return path
    with open(path, "wb") as handle:
        handle.write(data)
        handle.flush()
        os.fsync(handle.fileno())  # a full disk shows here, before any rename
    return path


def write_text(path: str | os.PathLike, text: str, *, atomic: bool = True) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically (see :func:`write_bytes`)."""
    return write_bytes(path, text.encode("utf-8"), atomic=atomic)


def json_text(obj: Any) -> str:
    """``obj`` as indented, key-sorted JSON text (NumPy scalars and arrays allowed)."""
    return json.dumps(obj, indent=2, sort_keys=True, default=_json_default) + "\n"


def _json_default(obj: Any) -> Any:
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.floating):
        return float(obj)
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def read_json(path: str | os.PathLike, name: str, missing: str | None = None) -> Any:
    """The JSON document in ``path``; one :class:`~prg.errors.UsageError` naming it as ``name``
    (``"trajectories file"``) when it does not exist (``missing``, if given, is that message) or
    is not readable JSON."""
    path = Path(path)
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise UsageError(missing or f"{name} {path} does not exist") from None
    except (OSError, ValueError) as err:
        raise UsageError(f"{name} {path} is not readable JSON ({err})") from None


def write_json(path: str | os.PathLike, obj: Any) -> Path:
    """Write :func:`json_text` of ``obj`` to ``path`` atomically."""
    return write_text(path, json_text(obj))


@contextmanager
def _staged(final: Path, move_into_place) -> Iterator[Path]:
    """A fresh hidden folder beside ``final`` for the block; ``move_into_place(staging, final)``
    when the block ends normally, with signals held; the folder is removed in every case."""
    final.parent.mkdir(parents=True, exist_ok=True)
    remove_stale(final.parent)
    staging = _temp_name(final)
    _remove(staging)
    staging.mkdir()
    try:
        try:
            yield staging
        except OSError as err:
            _raise_naming_final(err, staging, final)
        with deferred():  # a signal halfway through the moves would leave a mix
            move_into_place(staging, final)
    finally:
        _remove(staging)


def _swap_folder(staging: Path, final: Path) -> None:
    old = _temp_name(final, "old")
    if final.exists():
        os.replace(final, old)
    os.replace(staging, final)
    _remove(old)


def _move_entries(staging: Path, target: Path, owned: Sequence[str] = ()) -> None:
    target.mkdir(exist_ok=True)
    remove_stale(target)
    made = {item.name for item in staging.iterdir()}
    for name in sorted(set(owned) - made):  # an earlier run's output this run did not make
        _remove(target / name)
    for item in sorted(staging.iterdir()):
        destination = target / item.name
        old = _temp_name(destination, "old")
        if item.is_dir() and destination.is_dir():
            os.replace(destination, old)
        os.replace(item, destination)
        _remove(old)


def staged_folder(final: str | os.PathLike):
    """Context manager: an empty hidden folder beside ``final``; when the block ends normally it
    replaces ``final`` as a whole (the old folder is removed after the swap), otherwise it is
    removed and ``final`` is untouched."""
    return _staged(Path(final), _swap_folder)


def staged_outputs(target: str | os.PathLike, owned: Sequence[str] = ()):
    """Context manager: an empty hidden folder beside ``target``; when the block ends normally
    each entry is moved into ``target`` (created then; an entry replaces the one of the same
    name, other entries of ``target`` stay), otherwise it is removed and ``target`` is untouched.

    ``owned`` names the entries this kind of output may hold: those the block did not make this
    time are removed from ``target`` (an optional file left by an earlier run, e.g. a recording
    the new run was asked not to make, never sits stale beside the new outputs).

    Every output is complete in the staging folder before the first one is moved, so a failure
    while writing leaves no mix of old and new outputs.
    """
    return _staged(Path(target), lambda staging, final: _move_entries(staging, final, owned))


__all__ = [
    "atomic_path",
    "json_text",
    "move_into_place",
    "remove_stale",
    "staged_folder",
    "staged_outputs",
    "write_bytes",
    "write_json",
    "write_text",
]


_HASH_CHUNK = 1 << 16


def sha256_file(path: str | os.PathLike) -> str:
    """Hex SHA-256 of a file's bytes, read in chunks (a checkpoint or a download may be large)."""
    digest = hashlib.sha256()
    with Path(path).open("rb") as handle:
        while chunk := handle.read(_HASH_CHUNK):
            digest.update(chunk)
    return digest.hexdigest()


#: The fields a folder template may hold (``out_dir`` of ``prg-write``, ``prg-simulate`` and ``prg-export``).
FOLDER_FIELDS = ("text", "time")
FOLDER_TIME = "%Y%m%d-%H%M%S"
_FOLDER_TEXT_CHARS = 40


def folder_fields(template: str | os.PathLike, key: str = "out_dir") -> set[str]:
    """The ``{field}`` placeholders of an output-folder template (none: it names the folder).

    Raises
    ------
    UsageError
        Naming ``key`` when a field is not one of :data:`FOLDER_FIELDS` or a brace is unpaired.
    """
    try:
        fields = {f for _, f, _, _ in string.Formatter().parse(str(template)) if f is not None}
    except ValueError as err:
        raise UsageError(f"{key} {template}: {err} (placeholders: {{text}}, {{time}})") from None
    unknown = sorted(fields - set(FOLDER_FIELDS))
    if unknown:
        raise UsageError(
            f"{key} {template}: unknown placeholder {{{unknown[0]}}} "
            "(accepted: {text}, the word; {time}, YYYYmmdd-HHMMSS)"
        )
    return fields


@contextmanager
def word_folder(template: str | os.PathLike, text: str, key: str = "out_dir") -> Iterator[Path]:
    """The folder a word's outputs go to.

    A template without placeholders names the folder itself (reused: the outputs replace those
    of an earlier word there). Otherwise ``{text}`` becomes the word (letters and digits, any
    other run of characters ``_``, at most 40 characters) and ``{time}`` the local time
    (``YYYYmmdd-HHMMSS``), and the folder is made new: ``-2``, ``-3`` ... is appended while the
    name is taken (created exclusively, so two runs never share one). A new folder that is still
    empty when the block fails is removed again.

    Raises
    ------
    UsageError
        Naming ``key`` on a bad template or when the folder cannot be created.
    """
    if not folder_fields(template, key):
        yield Path(template)
        return
    name = re.sub(r"[^0-9A-Za-z]+", "_", text).strip("_")[:_FOLDER_TEXT_CHARS] or "word"
    base = Path(str(template).format(text=name, time=time.strftime(FOLDER_TIME)))
    try:
        base.parent.mkdir(parents=True, exist_ok=True)
        for n in itertools.count(1):
            folder = base if n == 1 else base.with_name(f"{base.name}-{n}")
            try:
                folder.mkdir()
                break
            except FileExistsError:
                continue
    except OSError as err:
        raise UsageError(f"{key} {base}: cannot create the folder ({err.strerror})") from None
    try:
        yield folder
    except BaseException:
        with suppress(OSError):
            folder.rmdir()  # only while empty: never outputs
        raise
