"""Signals as exceptions: SIGINT, SIGTERM and SIGHUP raise :class:`Interrupted` in the main
thread while :func:`raising_signals` is active (every command runs inside it, see
:func:`prg.commands.cli.handle_signals`).

The exception unwinds the work like any error: staged outputs are removed (:mod:`prg.files`),
pools stop their workers, Lightning tears its trainer down. Short steps that must not be cut in
two (moving finished outputs into place, starting a child process and recording it so it can be
stopped) run inside :func:`deferred`: a signal that arrives there is raised when the step ends.
A second signal while the first is being handled ends the process at once.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

HANDLED_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)

_state = threading.local()


class Interrupted(BaseException):
    """A handled signal arrived. A BaseException, like KeyboardInterrupt, so that no
    ``except Exception`` on the way (Lightning's, Hydra's, ours) swallows it."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def stop_children(timeout: float = 5.0) -> None:
    """Terminate this process's multiprocessing children (pool workers), then kill the ones
    still alive after ``timeout`` seconds."""
    children = multiprocessing.active_children()
    for child in children:
        child.terminate()
    for child in children:
        child.join(timeout)
        if child.is_alive():
            child.kill()
            child.join(1.0)


def _hung_up(args: threading.ExceptHookArgs) -> bool:
    """Whether a thread's uncaught exception is a peer hanging up (a connection reset or
    closed): what multiprocessing's file-descriptor sharing thread meets when a DataLoader
    worker it is handing a tensor to is stopped with the process."""
    return issubclass(args.exc_type, ConnectionError | EOFError)


def _quiet_hang_ups() -> None:
    """From now until :func:`raising_signals` ends: a thread's hang-up is dropped rather than
    printed as a traceback under the command's one line (every other exception still is)."""
    previous = threading.excepthook
    if getattr(previous, "prg_quiet", False):
        return

    def hook(args: threading.ExceptHookArgs) -> None:
        if not _hung_up(args):
            previous(args)

    hook.prg_quiet = True  # type: ignore[attr-defined]
    hook.previous = previous  # type: ignore[attr-defined]
    threading.excepthook = hook


def _on_signal(signum, frame) -> None:
    if getattr(_state, "depth", 0):
        _state.pending = signum  # raised when the deferred step ends
        return
    for sig in HANDLED_SIGNALS:
        signal.signal(sig, _exit_now)
    _quiet_hang_ups()  # the workers stop with us, some mid-handshake
    raise Interrupted(signum)


def _exit_now(signum, frame) -> None:
    stop_children(timeout=0.5)
    os._exit(128 + signum)


def hold() -> None:
    """Hold handled signals until the matching :func:`release` (nests)."""
    _state.depth = getattr(_state, "depth", 0) + 1


def release() -> None:
    """End one :func:`hold`; the last one raises a signal that arrived meanwhile. Nothing to end
    in a thread or process that holds nothing (a sweep's job run by a launcher elsewhere)."""
    if getattr(_state, "depth", 0) == 0:
        return
    _state.depth -= 1
    pending = getattr(_state, "pending", None)
    if pending is not None and _state.depth == 0:
        _state.pending = None
        _on_signal(pending, None)


@contextmanager
def deferred() -> Iterator[None]:
    """Hold a handled signal until the block ends, then raise it (nests)."""
    hold()
    try:
        yield
    finally:
        release()


@contextmanager
def raising_signals() -> Iterator[None]:
    """Raise :class:`Interrupted` for the handled signals inside the block (main thread only;
    elsewhere the block runs as is); the previous handlers are restored at the end."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {sig: signal.getsignal(sig) for sig in HANDLED_SIGNALS}
    for sig in HANDLED_SIGNALS:
        signal.signal(sig, _on_signal)
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if getattr(threading.excepthook, "prg_quiet", False):
            threading.excepthook = threading.excepthook.previous  # type: ignore[attr-defined]


__all__ = [
    "HANDLED_SIGNALS",
    "Interrupted",
    "deferred",
    "hold",
    "raising_signals",
    "release",
    "stop_children",
]
