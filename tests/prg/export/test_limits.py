"""Tests of ``prg.export.limits`` (moved from the suite on: a written word exported to real
machines (prg.export, prg-export): every file is read back with another reader (gcodeparser, an
HPGL parser written here, vpype's SVG reader, mcap-ros2's reader, numpy) and compared with what
the word, its DMP timing and the simulated arm say independently; the joint-limit check slows a
too-fast timing by the smallest factor and refuses what no slow-down fixes)."""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np
import pytest
from numpy.testing import assert_allclose

from prg.errors import UsageError
from prg.export import (
    LimitSettings,
)
from prg.export.limits import check_timing, divided_differences
from prg.export.robot import robot_trajectory
from prg.sim import SimSettings, simulate_word
from tests.helpers.export import PANDA_ARM, panda_datasheet, word, written  # noqa: F401 (fixtures)


@pytest.fixture(scope="module")
def rushed(word):
    """The Panda writes "h i" five times faster than the DMP's tempo."""
    return simulate_word(word, "panda", replace(SimSettings(), tempo=0.2), render=False)


# ----------------------------------------------------------------------------- limits


def test_divided_differences_of_a_known_motion_on_an_uneven_grid():
    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0.004, 0.006, 400))
    q = np.column_stack([np.sin(t), 0.5 * t**3])
    d = divided_differences(t, q)
    v, tv = d["velocity"]
    a, ta = d["acceleration"]
    j, _ = d["jerk"]
    assert v.shape == (399, 2) and a.shape == (398, 2) and j.shape == (397, 2)
    assert_allclose(v[:, 0], np.cos(tv), atol=1e-4)
    # on a cubic, the acceleration over three samples is exact at their mean time and the jerk
    # is exact (3) everywhere, however uneven the spacing
    assert_allclose(ta, (t[:-2] + t[1:-1] + t[2:]) / 3)
    assert_allclose(a[:, 1], 3 * ta, rtol=1e-6)
    assert_allclose(j[:, 1], 3.0, rtol=1e-4)


def test_a_too_fast_timing_is_slowed_by_the_smallest_factor_that_fits(
    rushed, panda_datasheet, caplog
):
    with caplog.at_level(logging.WARNING, logger="prg.export.robot"):
        trajectory = robot_trajectory(rushed, panda_datasheet)
    k = trajectory.slow_down
    assert k > 1.2
    assert "slowed" in caplog.text and f"{k:.4g}x" in caplog.text
    assert_allclose(trajectory.t, rushed.plan.t * k)
    limits = trajectory.limits
    sent = check_timing(trajectory.t, trajectory.q, limits)
    assert sent.slow_down == pytest.approx(1.0, abs=1e-9)
    limiting = trajectory.timing.limiting
    power = {"velocity": 1, "acceleration": 2, "jerk": 3}[limiting]
    assert sent.ratios[limiting] == pytest.approx(1.0, rel=1e-9)  # at the limit, not beyond
    assert check_timing(trajectory.t / 1.001, trajectory.q, limits).slow_down > 1.0
    assert trajectory.timing.ratios[limiting] == pytest.approx(k**power, rel=1e-9)


def test_the_slow_down_grows_in_proportion_to_the_speed_up(written, panda_datasheet):
    q = written.q_plan[:, PANDA_ARM]
    k5 = check_timing(written.plan.t / 5, q, panda_datasheet).slow_down
    k10 = check_timing(written.plan.t / 10, q, panda_datasheet).slow_down
    assert k5 > 1 and k10 == pytest.approx(2 * k5, rel=1e-9)


def test_no_timing_fits_beyond_the_slow_down_allowed_or_outside_the_joint_range(
    rushed, written, panda_datasheet
):
    with pytest.raises(
        UsageError, match=r"must be slowed [\d.]+x, more than limits\.max_slow_down=1\.1"
    ):
        robot_trajectory(rushed, panda_datasheet, LimitSettings(max_slow_down=1.1))
    q = written.q_plan[:, PANDA_ARM]
    upper = panda_datasheet.upper.copy()
    upper[3] = q[:, 3].max() - 0.01  # joint 4 ends 0.01 rad short of where the word takes it
    cramped = replace(panda_datasheet, upper=upper)
    with pytest.raises(UsageError, match=r"^panda_joint4 reaches -?[\d.]+ rad at t = .* outside"):
        check_timing(written.plan.t * 100, q, cramped)  # however slow
