"""Tests of ``prg.sim.workspace`` (moved from the suite on: the simulated robot writes: accuracy,
ink, lifts between words, workspace, IK, both arms, outputs, and the Rerun recording read back
from disk)."""

from __future__ import annotations

import numpy as np
import pytest

from prg.errors import UsageError
from prg.sim import (
    IKSolver,
    Paper,
    ReachMap,
    check_workspace,
    font_word,
)
from prg.sim.geometry import bounding_box
from tests.helpers.sim import _config


def test_a_word_too_large_for_the_workspace_is_refused_with_the_scale_that_fits():
    robot, settings = _config(paper=Paper(size_cm=(150.0, 100.0)))
    word = font_word("joy")
    low, high = bounding_box(word.points)
    anchor = (low + high) / 2
    with IKSolver(robot) as ik:
        reach = ReachMap(ik, settings.paper, (0.0, 1.5), step_cm=4.0)
        with pytest.raises(UsageError, match=r"out of reach; at most [\d.]+ cm wide") as err:
            check_workspace(word.points, anchor, np.zeros(2), 40.0, reach, "panda", "joy")
        fits = float(str(err.value).split("scale=")[-1].split()[0])
        assert 1.0 < fits < 40.0
        check_workspace(word.points, anchor, np.zeros(2), fits, reach, "panda", "joy")
        with pytest.raises(UsageError):
            check_workspace(word.points, anchor, np.zeros(2), fits * 1.05, reach, "panda", "joy")
