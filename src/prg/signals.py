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


def _on_signal(signum, frame) -> None:
    if getattr(_state, "depth", 0):
        _state.pending = signum  # raised when the deferred step ends
        return
    for sig in HANDLED_SIGNALS:
        signal.signal(sig, _exit_now)
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


__all__ = [
    "HANDLED_SIGNALS",
    "Interrupted",
    "deferred",
    "hold",
    "raising_signals",
    "release",
    "stop_children",
]
