"""Output folders that one run at a time may write: an advisory lock on a file in the folder.

Two trainings given the same ``checkpoint_dir`` or ``export_dir`` would otherwise both exit 0
with one run's ``model.ckpt`` beside the other's ``metrics.json``. :func:`folder_lock` takes an
exclusive ``flock`` on a hidden file beside the folder (``models/.muse.lock`` for
``models/muse``: the folder itself holds only outputs) for the whole run; a second run asking
for the same folder is refused at once with one line naming the holder (command, pid, host,
start time, written into the lock file by the holder). The kernel releases the lock when the
holder's file descriptor closes, so a run that dies in any way (``SIGKILL`` and power loss
included) never leaves a folder locked. A run that ends removes its lock file while it still
holds it (so a refused or finished run leaves nothing beside its outputs; one killed leaves an
empty, unlocked file); a run that locked a file another run removed meanwhile sees that the
path no longer names its file and tries again.

The lock is advisory: it keeps out the project's commands, not other programs.
"""

from __future__ import annotations

import fcntl
import os
import socket
import sys
import time
from collections.abc import Iterator, Sequence
from contextlib import ExitStack, contextmanager
from pathlib import Path

from prg.errors import UsageError


def lock_path(folder: str | os.PathLike) -> Path:
    """The lock file of ``folder``: ``.<name>.lock`` beside it (the same for every spelling of
    the folder's path, links resolved)."""
    resolved = Path(folder).resolve()
    if not resolved.name:  # the file system's root
        return resolved / ".lock"
    return resolved.with_name(f".{resolved.name}.lock")


def _holder() -> str:
    command = Path(sys.argv[0]).name if sys.argv and sys.argv[0] else "python"
    since = time.strftime("%Y-%m-%d %H:%M:%S")
    return f"{command}, pid {os.getpid()} on {socket.gethostname()}, since {since}"


@contextmanager
def folder_lock(folder: str | os.PathLike, key: str) -> Iterator[Path]:
    """Hold ``folder`` for this process for the block (its lock file, :func:`lock_path`, and the
    folders above it are created if missing; the folder itself is not).

    Raises
    ------
    UsageError
        Naming ``key``, the folder and the run that holds it, when another process holds it;
        or naming ``key`` when the lock file cannot be made.
    """
    folder = Path(folder)
    path = lock_path(folder)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
    except OSError as err:
        raise UsageError(
            f"{key} {folder}: cannot create its lock {path} ({err.strerror})"
        ) from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 512, 0).decode("utf-8", "replace").strip() or "another process"
            raise UsageError(
                f"{key} {folder} is being written by another run ({holder}): wait for it to "
                f"end or give another {key}"
            ) from None
        if not _names(path, fd):  # its holder removed it as we opened it: lock the new one
            os.close(fd)
            fd = -1
            with folder_lock(folder, key) as locked:
                yield locked
            return
        os.ftruncate(fd, 0)
        os.pwrite(fd, (_holder() + "\n").encode(), 0)
        try:
            yield folder
        finally:
            path.unlink(missing_ok=True)  # still held: no other run can be using this file
    finally:
        if fd >= 0:
            os.close(fd)  # releases the lock


def _names(path: Path, fd: int) -> bool:
    """Whether ``path`` still names the open file ``fd``."""
    try:
        return os.stat(path).st_ino == os.fstat(fd).st_ino
    except FileNotFoundError:
        return False


@contextmanager
def folder_locks(folders: Sequence[tuple[str | os.PathLike, str]]) -> Iterator[None]:
    """:func:`folder_lock` on each ``(folder, key)``, a folder given twice locked once."""
    seen: set[Path] = set()
    with ExitStack() as stack:
        for folder, key in folders:
            if lock_path(folder) not in seen:
                seen.add(lock_path(folder))
                stack.enter_context(folder_lock(folder, key))
        yield


__all__ = ["folder_lock", "folder_locks", "lock_path"]
