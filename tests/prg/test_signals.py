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
