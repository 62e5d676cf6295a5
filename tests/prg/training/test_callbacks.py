"""Tests of ``prg.training.callbacks`` not run through a whole fit (the rest are exercised by
the training runs of tests/prg/test_tracking.py and tests/prg/commands/test_train.py)."""

from __future__ import annotations

import time

import pytest

from prg.training.callbacks import FitTime


def test_fit_time_adds_a_resumed_fits_own_time_to_the_checkpointed_time():
    first = FitTime()
    first.begin()
    time.sleep(0.05)
    saved = first.state_dict()  # what a checkpoint of the first start holds
    assert saved["starts"] == 1 and saved["wall_s"] >= 0.05

    resumed = FitTime()
    resumed.load_state_dict({"cpu_s": 100.0, "wall_s": 200.0, "starts": saved["starts"]})
    resumed.begin()
    time.sleep(0.05)
    cpu_s, wall_s = resumed.elapsed()
    assert resumed.starts == 2
    assert 200.05 <= wall_s < 201.0 and 100.0 <= cpu_s < 101.0
    again = resumed.state_dict()
    assert again["starts"] == 2 and again["wall_s"] == pytest.approx(wall_s, abs=0.01)


def test_fit_time_counts_from_begin_not_from_construction():
    clock = FitTime()
    time.sleep(0.1)
    clock.begin()
    assert clock.elapsed()[1] < 0.1
