"""The simulator's numeric core (no PyBullet): paper frame, pen-down samples, ink, errors, plan."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from prg.errors import UsageError
from prg.sim.geometry import (
    pen_down_samples,
    runs,
)
from prg.sim.plan import PHASES, MotionSettings, plan_motion
from tests.helpers.sim_geometry import _two_words


def test_plan_writes_each_word_as_a_stroke_with_pen_up_moves_around_it():
    word, _ = _two_words()
    from prg.pipeline.timing import rest_to_rest_samples

    samples, duration = rest_to_rest_samples(word.points, 2.0, 0.3, 60)
    t = np.linspace(0, duration, len(samples))
    down = pen_down_samples(word.points, word.segment, word.segment_kinds, samples)
    settings = MotionSettings(lift_cm=1.5, approach_s=1.0, lower_s=0.5, lift_s=0.5, dwell_s=0.2)
    home = np.array([0.0, -10.0, 20.0])
    plan = plan_motion(samples, t, down, home, settings, dt=1 / 60)

    assert np.all(np.diff(plan.t) > 0)
    assert_allclose(plan.tip[0], home) and assert_allclose(plan.tip[-1], home)
    assert plan.n_strokes == 2
    names = [PHASES[i] for i in plan.phase]
    collapsed = [n for i, n in enumerate(names) if i == 0 or n != names[i - 1]]
    assert collapsed == [
        "approach",
        *["lower", "dwell", "write", "lift"],
        "travel",
        *["lower", "dwell", "write", "lift"],
        "retreat",
    ]
    # the pen touches the paper only from lowering to lifting, and writes at the DMP's times
    assert np.all(plan.tip[plan.pen_down, 2] == 0.0)
    assert np.all(plan.tip[np.isin(plan.phase, [0, 5, 6]), 2] > 1.0 - 1e-9)
    strokes = plan.strokes()
    assert_allclose(np.concatenate(strokes), samples[down])
    for k, (a, b) in enumerate(runs(down)):
        assert_allclose(np.diff(plan.t[plan.pen_down & (plan.stroke == k)]), np.diff(t[a:b]))


def test_plan_refuses_a_word_without_pen_down_samples():
    with pytest.raises(UsageError, match="no pen-down"):
        plan_motion(
            np.zeros((3, 2)), np.arange(3.0), np.zeros(3, bool), np.zeros(3), MotionSettings(), 0.1
        )
