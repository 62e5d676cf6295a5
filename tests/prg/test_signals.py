"""Tests of ``prg.signals`` (moved from the suite on: all-or-nothing writes (prg.files) and signals
held over the steps that must not be cut.

A write is made to fail halfway for real: the kernel's file-size limit (RLIMIT_FSIZE) makes a
write past it fail with EFBIG, the way a full disk fails with ENOSPC. Every writer of the
project must then leave the previous file exactly as it was, no temporary file beside it, and an
error that names the output the user asked for (not a hidden temporary name))."""

from __future__ import annotations

import os
import signal

import pytest

from prg.signals import Interrupted, deferred, raising_signals


def test_a_signal_inside_a_deferred_step_is_raised_when_the_step_ends():
    steps = []
    with raising_signals(), pytest.raises(Interrupted) as stopped:
        with deferred():
            os.kill(os.getpid(), signal.SIGTERM)
            for _ in range(1000):  # the handler runs between bytecodes: give it many
                steps.append(1)
            steps.append("end of step")
        steps.append("after the step")  # never reached
    assert stopped.value.signum == signal.SIGTERM
    assert steps[-1] == "end of step"


def test_a_signal_outside_a_deferred_step_is_raised_at_once():
    steps = []
    with raising_signals(), pytest.raises(Interrupted):
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(1000):
            steps.append(1)
    assert len(steps) < 1000


def _thread_raising(error: BaseException) -> None:
    import threading

    def run():
        raise error

    thread = threading.Thread(target=run)
    thread.start()
    thread.join()


def test_once_stopping_a_threads_hang_up_is_quiet_and_other_errors_are_not(monkeypatch):
    import threading

    seen = []  # what reaches the hook in place before (Python's prints a traceback)
    monkeypatch.setattr(threading, "excepthook", lambda args: seen.append(args.exc_type))
    before = threading.excepthook
    with raising_signals(), pytest.raises(Interrupted):
        _thread_raising(ConnectionResetError(104, "Connection reset by peer"))
        assert seen == [ConnectionResetError]  # not stopping yet: it goes through
        os.kill(os.getpid(), signal.SIGTERM)
        for _ in range(1000):
            pass
    # the stop left the quiet hook in place until the block's end; the old one is back after
    assert threading.excepthook is before
    seen.clear()
    stopped = False
    with raising_signals():
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            for _ in range(10**6):  # the handler runs between bytecodes, well before the end
                pass
        except Interrupted:  # while the stop unwinds, as multiprocessing's sharer thread meets it
            stopped = True
            _thread_raising(ConnectionResetError(104, "Connection reset by peer"))
            _thread_raising(BrokenPipeError(32, "Broken pipe"))
            _thread_raising(EOFError())
            _thread_raising(ValueError("a real bug"))
    assert stopped and seen == [ValueError]
