"""Tests of ``prg.pipeline.dmp.targets`` (moved from the suite on: discrete DMP (prg.pipeline.dmp):
reproduction, generalisation, exactness of the rollout, fit)."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from prg.pipeline.dmp import (
    fit_dmp,
    forcing_targets,
)
from tests.helpers.dmp import word_like


def test_five_point_differences_make_targets_exact_for_quartic_paths():
    t = np.linspace(0.0, 2.0, 41)  # tau = 2
    y = np.column_stack([t**4 - 3 * t**3 + t, 2 * t**2 - t**4 / 5])
    yd = np.column_stack([4 * t**3 - 9 * t**2 + 1, 4 * t - 4 * t**3 / 5])
    ydd = np.column_stack([12 * t**2 - 18 * t, 4 - 12 * t**2 / 5])
    k, d, a = 100.0, 20.0, 3.0
    x, targets = forcing_targets(y, tau=2.0, stiffness=k, damping=d, alpha_x=a)
    assert_allclose(x, np.exp(-a * t / 2.0))
    g, y0 = y[-1], y[0]
    expected = (4 * ydd + d * 2 * yd) / k - (g - y) + np.outer(x, g - y0)
    assert_allclose(targets, expected, atol=1e-9)


def test_the_goal_velocity_term_and_the_documented_defaults():
    """With ``velocities="demonstrated"`` the goal moves, g_m(t) = g - g' (tau - t), and the
    targets lose ``D tau g' / K`` (g' the path's last velocity, exact for a quartic); left out,
    the goal is at rest. (``tau`` cannot change the targets of given points: y'' scales as
    tau^-2, y' as tau^-1 and the phase runs on t / tau.)"""
    t = np.linspace(0.0, 2.0, 41)
    y = np.column_stack([t**4 - 3 * t**3 + t, 2 * t**2 - t**4 / 5])
    end_velocity = np.array([4 * 8 - 9 * 4 + 1, 4 * 2 - 4 * 8 / 5])
    k, d = 100.0, 20.0
    _, rest = forcing_targets(y, tau=2.0, stiffness=k, damping=d)
    _, moving = forcing_targets(y, tau=2.0, stiffness=k, damping=d, velocities="demonstrated")
    expected = rest + np.outer(2.0 - t, end_velocity) - d * 2.0 * end_velocity / k
    assert_allclose(moving, expected, atol=1e-9)
    x_default, default = forcing_targets(y, stiffness=k, damping=d)
    assert_allclose(default, rest, rtol=1e-12, atol=1e-12)
    assert_allclose(x_default, forcing_targets(y, tau=5.0)[0], rtol=1e-12)


def test_second_differences_are_fourth_order_in_the_interior():
    # five-point centred stencils: halving the step divides the error of y'' by ~16 (a stencil
    # off the centre is third order: ~8)
    errors = []
    for n in (101, 201):
        t = np.linspace(0.0, 1.0, n)
        y = np.column_stack([np.sin(3 * t), np.cos(5 * t)])
        ydd = np.column_stack([-9 * np.sin(3 * t), -25 * np.cos(5 * t)])
        x, targets = forcing_targets(y, tau=1.0, stiffness=1.0, damping=0.0)
        exact = ydd - (y[-1] - y) + np.outer(x, y[-1] - y[0])
        errors.append(np.abs(targets - exact)[3:-3].max())
    assert errors[0] / errors[1] > 13.0


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"stiffness": 0.0}, "stiffness: expected a number > 0"),
        ({"damping": -1.0}, "damping: expected a number >= 0"),
        ({"alpha_x": -2.0}, "alpha_x: expected a number > 0"),
        ({"width_factor": 0.0}, "width_factor: expected a number > 0"),
    ],
)
def test_bad_dynamics_constants_are_named_by_the_fit_and_the_targets(kwargs, match):
    points = word_like(50, loops=1)
    with pytest.raises(ValueError, match=match):
        fit_dmp(points, **kwargs)
    if "width_factor" not in kwargs:
        with pytest.raises(ValueError, match=match):
            forcing_targets(points, **kwargs)
    with pytest.raises(ValueError, match="tau: expected a number > 0"):
        forcing_targets(points, tau=-1.0)
