"""Tests of ``prg.pipeline.dmp.integration`` (moved from the suite on: discrete DMP
(prg.pipeline.dmp): reproduction, generalisation, exactness of the rollout, fit)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from numpy.testing import assert_allclose, assert_array_equal

from prg.pipeline.dmp import (
    fit_dmp,
    rollout,
)
from tests.helpers.dmp import moving_curve, rk4_reference, rmse, word, word_dmp, word_like  # noqa: F401 (fixtures)
from tests.helpers.properties import demonstrations, examples, log_uniform

# ----------------------------------------------------------------------------- reproduction


def test_reproduces_a_20_cm_1000_point_word_within_a_tenth_of_a_millimetre(word, word_dmp):
    out = rollout(word_dmp)
    assert out.shape == word.shape
    assert rmse(out, word) < 0.01  # cm


def test_rollout_starts_at_y0_and_ends_at_the_goal(word, word_dmp):
    out = rollout(word_dmp)
    assert_array_equal(out[0], word[0])
    assert_allclose(out[-1], word[-1], atol=1e-3)


def test_the_same_default_basis_count_holds_for_short_and_long_words():
    for n in (500, 2000):
        points = word_like(n, loops=round(12 * n / 1000))
        assert rmse(rollout(fit_dmp(points)), points) < 0.01


def test_a_new_start_starts_there_and_still_ends_at_the_goal(word_dmp):
    start = word_dmp.y0 + np.array([-2.0, 1.0])
    out = rollout(word_dmp, y0=start)
    assert_array_equal(out[0], start)
    assert np.linalg.norm(out[-1] - word_dmp.goal) < 0.03 * math.sqrt(5.0)


def test_a_slower_tempo_traces_the_same_path(word_dmp):
    path = rollout(word_dmp)
    assert_allclose(rollout(word_dmp, tau=2 * word_dmp.tau), path, atol=1e-12)
    # twice the duration at the same step: twice the samples, the same path every other sample
    slow = rollout(word_dmp, tau=2 * word_dmp.tau, dt=word_dmp.tau / (word_dmp.n_samples - 1))
    assert slow.shape[0] == 2 * word_dmp.n_samples - 1
    assert_allclose(slow[::2], path, atol=1e-4)  # both within 1 µm of the exact ODE solution


# ----------------------------------------------------------------------------- exactness


def test_vectorised_rollout_matches_a_per_step_rk4_integration(word_dmp):
    # what is left is the cubic interpolation of the input between samples: 1.4e-5 cm here
    # (a cubic through four samples that are not the nearest ones leaves 2.4e-5 cm)
    reference = rk4_reference(word_dmp, word_dmp.n_samples)
    assert_allclose(rollout(word_dmp), reference, rtol=0, atol=2e-5)
    # and it shrinks like h^4 on finer grids: 2x the samples, ~16x closer
    finer = rollout(word_dmp, n_samples=2 * word_dmp.n_samples - 1)[::2]
    assert np.abs(finer - reference).max() < np.abs(rollout(word_dmp) - reference).max() / 8


def test_integrating_on_the_output_grid_is_close_and_the_default_finer_grid_closer(word):
    # 0.7 basis functions per sample, as words are fitted (generate.basis_per_100_samples)
    dense = fit_dmp(word, tau=3.0, n_basis=700)
    reference = rk4_reference(dense, word.shape[0], substeps=6)  # within 1e-9 cm of 30
    coarse = np.abs(rollout(dense, samples_per_basis=1) - reference).max()
    default = np.abs(rollout(dense) - reference).max()
    assert coarse < 5e-5  # cm: 1.4e-5 here
    assert default < coarse / 10


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"n_samples": 1}, "n_samples: expected an integer >= 2"),
        ({"goal": [1.0, 2.0, 3.0]}, r"goal: expected shape \(2,\)"),
        ({"y0": [np.nan, 0.0]}, "y0: expected finite"),
        ({"tau": 0}, "tau: expected a number > 0"),
        ({"dt": -0.1}, "dt: expected a number > 0"),
        ({"dt": 0.1, "n_samples": 10}, "n_samples, dt: give one"),
        ({"samples_per_basis": 0}, "samples_per_basis: expected an integer >= 1"),
        ({"samples_per_basis": True}, "samples_per_basis: expected an integer >= 1"),
        ({"start_velocity": [1.0]}, r"start_velocity: expected shape \(2,\), got shape \(1,\)"),
        ({"goal_velocity": [1.0, 2.0, 3.0]}, r"goal_velocity: expected shape \(2,\)"),
    ],
)
def test_bad_rollout_inputs_raise_value_error_naming_the_argument(word_dmp, kwargs, match):
    with pytest.raises(ValueError, match=match):
        rollout(word_dmp, **kwargs)


def test_a_time_step_as_long_as_the_movement_gives_its_two_ends(word_dmp):
    """``dt`` gives round(tau / dt) + 1 samples, at least 2: the start and the end."""
    ends = rollout(word_dmp, dt=word_dmp.tau)
    assert ends.shape == (2, 2)
    assert_array_equal(ends[0], word_dmp.y0)
    assert rollout(word_dmp, dt=10 * word_dmp.tau).shape == (2, 2)
    assert rollout(word_dmp, dt=word_dmp.tau / 2).shape == (3, 2)


# ----------------------------------------------------------------------------- robustness


@settings(max_examples=60, deadline=None)
@given(
    points=st.integers(3, 300).flatmap(
        lambda n: arrays(np.float64, (n, 2), elements=st.floats(-100.0, 100.0))
    ),
    tau=st.floats(0.05, 20.0),
    goal_shift=arrays(np.float64, 2, elements=st.floats(-50.0, 50.0)),
)
def test_any_bounded_finite_points_give_finite_rollouts(points, tau, goal_shift):
    dmp = fit_dmp(points, tau=tau)
    assert np.all(np.isfinite(dmp.weights))
    out = rollout(dmp)
    assert out.shape == points.shape and np.all(np.isfinite(out))
    moved = rollout(dmp, goal=points[-1] + goal_shift, n_samples=50)
    assert np.all(np.isfinite(moved))


def test_demonstrated_velocities_reproduce_a_path_that_starts_and_ends_moving():
    tau = 2.0
    path = moving_curve(tau=tau)
    step = tau / (len(path) - 1)
    at_rest = rollout(fit_dmp(path, tau=tau, n_basis=100))
    moving = fit_dmp(path, tau=tau, n_basis=100, velocities="demonstrated")
    out = rollout(moving)
    # the analytic first and last velocities of moving_curve: 4 + 0.6 * 6 pi / tau, 0.5
    assert_allclose(moving.start_velocity, [4.0 + 0.6 * 3 * np.pi, 0.5], rtol=1e-6)
    assert_allclose(moving.goal_velocity, [4.0 + 0.6 * 3 * np.pi, 0.5], rtol=1e-6)
    assert rmse(out, path) < 1e-3  # cm
    assert rmse(at_rest, path) > 50 * rmse(out, path)  # the start transient of a DMP at rest
    # the rollout leaves its first and last samples at the demonstrated velocities, not at rest
    # (one-sided second-order differences)
    end = (3 * out[-1] - 4 * out[-2] + out[-3]) / (2 * step)
    start = (-3 * out[0] + 4 * out[1] - out[2]) / (2 * step)
    assert_allclose(end, moving.goal_velocity, rtol=5e-3)
    assert_allclose(start, moving.start_velocity, rtol=5e-3)


@examples(20)
@given(
    point=arrays(np.float64, 2, elements=st.floats(-1e4, 1e4)),
    n=st.integers(3, 500),
    tau=log_uniform(-2, 2),
)
def test_a_constant_demonstration_gives_a_constant_rollout(point, n, tau):
    demo = np.tile(point, (n, 1))
    out = rollout(fit_dmp(demo, tau=tau))
    np.testing.assert_allclose(out, demo, rtol=0, atol=1e-12 * (1 + np.abs(point).max()))


@examples(40)
@given(
    demo=demonstrations(),
    moves=st.tuples(*[st.tuples(st.floats(-math.pi, math.pi), st.floats(0.01, 1.0))] * 2),
    size=log_uniform(-2, 2),
    stretch=log_uniform(-1, 1),
)
def test_a_new_start_goal_or_tempo_moves_the_rollout_smoothly(demo, moves, size, stretch):
    """The DMP is linear in start and goal: a new goal adds ``(g' - g) s(t)`` with ``s`` rising
    from 0 to about 0.975 at ``t = tau`` (module docstring); a new tempo keeps the path."""
    dmp = fit_dmp(demo)
    base = rollout(dmp)
    extent = np.ptp(demo, axis=0).max()
    tol = 1e-9 * (np.abs(demo).max() + size * extent)
    dg, dy = (size * extent * m * np.array([math.cos(a), math.sin(a)]) for a, m in moves)
    moved = rollout(dmp, goal=dmp.goal + dg)
    assert np.all(np.isfinite(moved))
    s = (moved - base) @ dg / (dg @ dg)
    np.testing.assert_allclose(moved - base, np.outer(s, dg), rtol=0, atol=tol)
    assert s[0] == 0 and np.all(np.diff(s) >= -1e-9) and 0.97 <= s[-1] <= 1.0
    restarted = rollout(dmp, y0=dmp.y0 + dy)
    np.testing.assert_array_equal(restarted[0], dmp.y0 + dy)
    r = (restarted - base) @ dy / (dy @ dy)
    np.testing.assert_allclose(restarted - base, np.outer(r, dy), rtol=0, atol=tol)
    assert np.all(np.diff(r) <= 1e-9) and 0.0 <= r[-1] <= 0.03
    np.testing.assert_allclose(rollout(dmp, tau=dmp.tau * stretch), base, rtol=0, atol=tol)
