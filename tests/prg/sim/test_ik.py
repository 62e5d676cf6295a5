"""Tests of ``prg.sim.ik`` (moved from the suite on: the simulated robot writes: accuracy, ink,
lifts between words, workspace, IK, both arms, outputs, and the Rerun recording read back from
disk)."""

from __future__ import annotations

import numpy as np
import pytest

from prg.sim import (
    IKSolver,
    UnreachableError,
)
from tests.helpers.sim import _config


def test_null_space_ik_alone_misses_by_millimetres_and_the_refinement_fixes_it():
    robot, settings = _config()
    target = settings.paper.to_world([[5.0, 5.0, 0.0]])[0]
    with IKSolver(robot, settings.ik) as ik:
        refined = ik.solve(target)[1]
    from dataclasses import replace

    with IKSolver(robot, replace(settings.ik, method="null_space")) as ik:
        plain = ik.solve(target)[1]
    assert refined < 1e-6 < 1e-4 < plain


def test_an_unreachable_target_is_named():
    robot, _ = _config()
    with IKSolver(robot) as ik, pytest.raises(UnreachableError, match=r"\(2\.0000, 0\.0000"):
        ik.solve_path(np.array([[0.5, 0.0, 0.9], [2.0, 0.0, 0.9]]))
