"""Discrete DMP (prg.pipeline.dmp): reproduction, generalisation, exactness of the rollout, fit."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from numpy.testing import assert_allclose, assert_array_equal

from prg.errors import UsageError
from prg.pipeline import dmp as dmp_module
from prg.pipeline.dmp import (
    DMP,
    basis_count,
    basis_functions,
    design_matrix,
    fit_dmp,
    forcing_targets,
    rollout,
    uniform_in_time,
)


def word_like(n: int = 1000, loops: int = 12, width: float = 20.0, height: float = 4.0):
    """A cursive-like curve in cm: ``loops`` loops of varying height, ``width`` x ``height``.

    Sampled uniformly in time with a minimum-jerk time course, so the pen starts and ends at rest.
    """
    t = np.linspace(0.0, 1.0, n)
    s = 10 * t**3 - 15 * t**4 + 6 * t**5
    angle = 2 * np.pi * loops * s
    amplitude = 0.55 + 0.45 * np.sin(2 * np.pi * 2.3 * s + 0.7) ** 2  # ascenders and x-height
    x = s - 0.045 * np.sin(angle)
    y = amplitude * (1 - np.cos(angle)) + 0.15 * np.sin(np.pi * s)
    x = (x - x.min()) / np.ptp(x) * width
    y = (y - y.min()) / np.ptp(y) * height
    return np.column_stack([x, y])


def rmse(a: np.ndarray, b: np.ndarray) -> float:
    """Root mean squared Euclidean distance between corresponding points."""
    return float(np.sqrt(np.mean(np.sum((a - b) ** 2, axis=1))))


def rk4_reference(dmp: DMP, n_samples: int, y0=None, goal=None, tau=None, substeps: int = 10):
    """Per-step RK4 integration of the DMP's ODE, written from the formulation, not the code.

    ``y' = v / tau``, ``v' = (K (g_m - y) + D (tau g' - v) - K (g - y0) x + K f(x)) / tau`` with
    the moving goal ``g_m = g - g' (tau - t)``, ``x = exp(-alpha_x t / tau)`` and ``f =
    design_matrix(x) @ weights``, from ``(y0, tau y0')``, ``substeps`` RK4 steps between output
    samples (``y0'``, ``g'``: the DMP's start and goal velocities).
    """
    y0 = dmp.y0 if y0 is None else np.asarray(y0, float)
    goal = dmp.goal if goal is None else np.asarray(goal, float)
    tau = dmp.tau if tau is None else tau
    goal_v = dmp.goal_velocity
    k_, d_ = dmp.stiffness, dmp.damping
    steps = (n_samples - 1) * substeps
    h = tau / steps
    half_times = np.arange(2 * steps + 1) * (h / 2)  # every RK4 stage time
    x_half = np.exp(-dmp.alpha_x * half_times / tau)
    f_half = design_matrix(x_half, dmp.centres, dmp.widths) @ dmp.weights

    def acceleration(j: int, y: np.ndarray, v: np.ndarray) -> np.ndarray:
        moving_goal = goal - goal_v * (tau - half_times[j])
        return (
            k_ * (moving_goal - y)
            + d_ * (tau * goal_v - v)
            - k_ * (goal - y0) * x_half[j]
            + k_ * f_half[j]
        ) / tau

    y, v = y0.copy(), tau * dmp.start_velocity
    out = [y.copy()]
    for i in range(steps):
        j = 2 * i
        k1y, k1v = v / tau, acceleration(j, y, v)
        k2y, k2v = (v + h / 2 * k1v) / tau, acceleration(j + 1, y + h / 2 * k1y, v + h / 2 * k1v)
        k3y, k3v = (v + h / 2 * k2v) / tau, acceleration(j + 1, y + h / 2 * k2y, v + h / 2 * k2v)
        k4y, k4v = (v + h * k3v) / tau, acceleration(j + 2, y + h * k3y, v + h * k3v)
        y = y + h / 6 * (k1y + 2 * k2y + 2 * k3y + k4y)
        v = v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        if (i + 1) % substeps == 0:
            out.append(y.copy())
    return np.array(out)


@pytest.fixture(scope="module")
def word():
    points = word_like()
    assert points.shape == (1000, 2)
    assert_allclose(np.ptp(points, axis=0), [20.0, 4.0])
    return points


@pytest.fixture(scope="module")
def word_dmp(word):
    return fit_dmp(word, tau=3.0)


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


def test_a_demonstration_that_starts_moving_leaves_the_documented_transient():
    # the DMP starts at rest: a stroke at constant speed v0 is followed with -v0 t exp(-w t)
    t = np.linspace(0.0, 1.0, 1000)
    stroke = np.column_stack([20.0 * t, np.zeros_like(t)])
    error = rollout(fit_dmp(stroke))[:, 0] - stroke[:, 0]
    omega = math.sqrt(dmp_module.STIFFNESS)
    assert_allclose(error, -20.0 * t * np.exp(-omega * t), atol=1e-4)


# ----------------------------------------------------------------------------- generalisation


def test_a_new_goal_adds_a_smooth_transition_and_keeps_the_shape(word_dmp):
    # The modified (Hoffmann/Pastor) DMP is linear in the goal: a new goal adds
    # (goal_new - goal) * s(t), s the zero-weight DMP from 0 to 1 (computed here by RK4),
    # so the written shape is kept and only shifted smoothly towards the new end.
    shift = np.array([1.5, -0.8])
    moved = rollout(word_dmp, goal=word_dmp.goal + shift)
    original = rollout(word_dmp)
    unit = DMP(
        weights=np.zeros((word_dmp.n_basis, 1)),
        y0=[0.0],
        goal=[1.0],
        tau=word_dmp.tau,
        stiffness=word_dmp.stiffness,
        damping=word_dmp.damping,
        alpha_x=word_dmp.alpha_x,
        centres=word_dmp.centres,
        widths=word_dmp.widths,
        n_samples=word_dmp.n_samples,
    )
    s = rk4_reference(unit, word_dmp.n_samples, substeps=2)[:, 0]
    assert np.all(np.diff(s) >= -1e-12) and 0.97 < s[-1] <= 1.0
    assert_allclose(moved - original, np.outer(s, shift), atol=1e-6)
    # the end point moves to the new goal (within what s has left at t = tau)
    assert np.linalg.norm(moved[-1] - (word_dmp.goal + shift)) < 0.03 * np.linalg.norm(shift)


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


def test_rollout_matches_rk4_with_new_start_goal_tempo_and_few_samples(word_dmp):
    # 300 samples for 200 basis functions: the rollout integrates on a finer grid
    kwargs = {"y0": [1.0, 2.0], "goal": [18.0, -1.0], "tau": 1.7}
    out = rollout(word_dmp, n_samples=300, **kwargs)
    assert_allclose(out, rk4_reference(word_dmp, 300, substeps=30, **kwargs), rtol=0, atol=5e-5)


def test_integrating_on_the_output_grid_is_close_and_the_default_finer_grid_closer(word):
    # 0.7 basis functions per sample, as words are fitted (generate.basis_per_100_samples)
    dense = fit_dmp(word, tau=3.0, n_basis=700)
    reference = rk4_reference(dense, word.shape[0], substeps=6)  # within 1e-9 cm of 30
    coarse = np.abs(rollout(dense, samples_per_basis=1) - reference).max()
    default = np.abs(rollout(dense) - reference).max()
    assert coarse < 5e-5  # cm: 1.4e-5 here
    assert default < coarse / 10


def test_the_banded_design_matrix_equals_the_dense_one():
    x = np.exp(-dmp_module.ALPHA_X * np.linspace(-0.2, 1.2, 2001))
    for n_basis in (1, 3, 25, 26, 60, 75, 200, 500):
        centres, widths = basis_functions(n_basis)
        start, values = dmp_module._design_band(x, centres, widths)
        banded = dmp_module._dense(start, values, n_basis)
        assert_allclose(banded, design_matrix(x, centres, widths), rtol=0, atol=1e-15)


# ----------------------------------------------------------------------------- the fit


def test_basis_functions_are_evenly_spaced_in_time_with_widths_from_the_spacing():
    centres, widths = basis_functions(50, alpha_x=3.0)
    assert_allclose(-np.log(centres) / 3.0, np.linspace(0, 1, 50), atol=1e-15)
    spacing = centres[:-1] - centres[1:]
    assert_allclose(widths[:-1], 1 / (2 * spacing**2))
    assert widths[-1] == widths[-2]


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


def _design_for(dmp: DMP, n: int) -> np.ndarray:
    """The design matrix from the docstring formula, built here from the DMP's fields."""
    x = np.exp(-dmp.alpha_x * np.arange(n) / (n - 1))
    psi = np.exp(-dmp.widths * (x[:, None] - dmp.centres) ** 2)
    return x[:, None] * psi / psi.sum(axis=1, keepdims=True)


def test_fit_is_the_single_ridge_solution_for_all_weights_and_dims():
    points = word_like(400, loops=5)
    lam = 1e-6
    dmp = fit_dmp(points, tau=1.5, n_basis=60, regularisation=lam)
    _, targets = forcing_targets(points, tau=1.5)
    phi = _design_for(dmp, 400)
    # ridge on the mean squared error = least squares on the stacked system
    stacked = np.vstack([phi / math.sqrt(400), math.sqrt(lam) * np.eye(60)])
    padded = np.vstack([targets / math.sqrt(400), np.zeros((60, 2))])
    expected = np.linalg.lstsq(stacked, padded, rcond=None)[0]
    assert dmp.weights.shape == (60, 2)
    assert_allclose(dmp.weights, expected, rtol=1e-7, atol=1e-9 * np.abs(expected).max())


def test_without_regularisation_the_fit_is_plain_least_squares():
    points = word_like(300, loops=4)
    dmp = fit_dmp(points, n_basis=40, regularisation=0.0)
    _, targets = forcing_targets(points)
    expected = np.linalg.lstsq(_design_for(dmp, 300), targets, rcond=None)[0]
    assert_allclose(dmp.weights, expected, rtol=1e-8, atol=1e-10 * np.abs(expected).max())


def test_basis_count_scales_with_points_and_is_clipped():
    assert basis_count(1000, per_100_points=20, minimum=5, maximum=900) == 200
    assert basis_count(10, per_100_points=20, minimum=15, maximum=900) == 15
    assert basis_count(10_000, per_100_points=20, minimum=5, maximum=300) == 300
    counts = [basis_count(n) for n in range(1, 5000, 37)]
    assert counts == sorted(counts)
    assert fit_dmp(word_like(700, loops=8)).n_basis == basis_count(700)


# ----------------------------------------------------------------------------- storage


def test_to_dict_from_dict_round_trip_through_json_gives_identical_rollouts(word_dmp):
    text = json.dumps(word_dmp.to_dict())
    restored = DMP.from_dict(json.loads(text))
    assert restored.n_basis == word_dmp.n_basis and restored.tau == word_dmp.tau
    assert_array_equal(rollout(restored), rollout(word_dmp))
    assert_array_equal(rollout(restored, goal=[3.0, 3.0]), rollout(word_dmp, goal=[3.0, 3.0]))


def test_dmp_arrays_are_read_only(word_dmp):
    with pytest.raises(ValueError, match="read-only"):
        word_dmp.weights[0, 0] = 1.0


# ----------------------------------------------------------------------------- bad inputs


@pytest.mark.parametrize(
    ("points", "kwargs", "match"),
    [
        ([[0, 0], [1, np.nan], [2, 0]], {}, "points: expected finite"),
        ([[0, 0], [1, np.inf], [2, 0]], {}, "points: expected finite"),
        ([[0, 0], [1, 1]], {}, r"points: .*n >= 3"),
        ([0.0, 1.0, 2.0], {}, "points: expected a 2-D array"),
        (np.zeros((4, 2, 2)), {}, "points: expected a 2-D array"),
        (np.zeros((5, 0)), {}, r"points: .*dims >= 1"),
        ([["a", "b"], ["c", "d"], ["e", "f"]], {}, "points: expected an array of numbers"),
        (np.zeros((5, 2)), {"n_basis": 0}, "n_basis: expected an integer >= 1"),
        (np.zeros((5, 2)), {"n_basis": 2.5}, "n_basis: expected an integer >= 1"),
        (np.zeros((5, 2)), {"tau": 0.0}, "tau: expected a number > 0"),
        (np.zeros((5, 2)), {"tau": -1.0}, "tau: expected a number > 0"),
        (np.zeros((5, 2)), {"tau": np.nan}, "tau: expected a finite number"),
        (np.zeros((5, 2)), {"regularisation": -1e-3}, "regularisation: expected a number >= 0"),
    ],
)
def test_bad_fit_inputs_raise_value_error_naming_the_argument(points, kwargs, match):
    with pytest.raises(ValueError, match=match) as info:
        fit_dmp(points, **kwargs)
    assert isinstance(info.value, UsageError)


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
    ],
)
def test_bad_rollout_inputs_raise_value_error_naming_the_argument(word_dmp, kwargs, match):
    with pytest.raises(ValueError, match=match):
        rollout(word_dmp, **kwargs)


def test_from_dict_rejects_incomplete_or_inconsistent_data(word_dmp):
    data = word_dmp.to_dict()
    with pytest.raises(ValueError, match=r"missing keys \['widths'\]"):
        DMP.from_dict({k: v for k, v in data.items() if k != "widths"})
    with pytest.raises(ValueError, match=r"centres: expected shape"):
        DMP.from_dict({**data, "centres": data["centres"][:-1]})
    with pytest.raises(ValueError, match="n_basis"):
        DMP.from_dict({**data, "n_basis": 3})


def test_basis_count_rejects_bad_bounds():
    with pytest.raises(ValueError, match="maximum: expected an integer >= 30"):
        basis_count(100, minimum=30, maximum=10)
    with pytest.raises(ValueError, match="per_100_points: expected a number > 0"):
        basis_count(100, per_100_points=0)


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


# ----------------------------------------------------------------------------- non-default arguments
# Every public constant of the DMP can be changed; a formula that uses the module default where
# it should use the argument is invisible at the defaults, so these tests use other values and
# check against formulas written here and against the per-step RK4 integration.

NON_DEFAULT = [
    # stiffness, damping (None: critical), alpha_x, width_factor, n_basis, tau, regularisation
    pytest.param(400.0, None, 3.0, 1.5, 150, 0.7, 1e-12, id="stiff-critical"),
    pytest.param(100.0, 12.0, 6.0, 0.8, 220, 2.0, 1e-12, id="underdamped"),
    pytest.param(60.0, 30.0, 2.0, 1.2, 180, 1.3, 1e-9, id="overdamped-slow-phase"),
]


def _fit_with(points, stiffness, damping, alpha_x, width_factor, n_basis, tau, lam):
    """``fit_dmp`` with every constant given (a NON_DEFAULT row)."""
    return fit_dmp(
        points,
        tau=tau,
        n_basis=n_basis,
        regularisation=lam,
        stiffness=stiffness,
        damping=damping,
        alpha_x=alpha_x,
        width_factor=width_factor,
    )


@pytest.mark.parametrize(
    ("stiffness", "damping", "alpha_x", "width_factor", "n_basis", "tau", "lam"), NON_DEFAULT
)
def test_non_default_constants_are_stored_used_and_reproduce_the_demonstration(
    stiffness, damping, alpha_x, width_factor, n_basis, tau, lam
):
    points = word_like(600, loops=7)
    dmp = _fit_with(points, stiffness, damping, alpha_x, width_factor, n_basis, tau, lam)
    # every field, against the documented formulas
    want_damping = 2.0 * math.sqrt(stiffness) if damping is None else damping
    assert (dmp.stiffness, dmp.damping, dmp.alpha_x, dmp.tau) == (
        stiffness,
        pytest.approx(want_damping, rel=1e-15),
        alpha_x,
        tau,
    )
    assert (dmp.n_basis, dmp.dims, dmp.n_samples) == (n_basis, 2, 600)
    assert_array_equal(dmp.y0, points[0])
    assert_array_equal(dmp.goal, points[-1])
    centres = np.exp(-alpha_x * np.arange(n_basis) / (n_basis - 1))
    spacing = centres[:-1] - centres[1:]
    assert_allclose(dmp.centres, centres, rtol=1e-13)
    assert_allclose(dmp.widths[:-1], 1 / (2 * (width_factor * spacing) ** 2), rtol=1e-9)
    assert dmp.widths[-1] == dmp.widths[-2]
    # the weights are the ridge solution for the targets of *these* constants
    _, targets = forcing_targets(points, tau, stiffness, want_damping, alpha_x)
    phi = _design_for(dmp, 600)
    stacked = np.vstack([phi / math.sqrt(600), math.sqrt(lam) * np.eye(n_basis)])
    padded = np.vstack([targets / math.sqrt(600), np.zeros((n_basis, 2))])
    expected = np.linalg.lstsq(stacked, padded, rcond=None)[0]
    assert_allclose(dmp.weights, expected, rtol=1e-6, atol=1e-8 * np.abs(expected).max())
    # the rollout integrates the ODE of these constants (RK4 from the formulation) ...
    out = rollout(dmp)
    assert_allclose(out, rk4_reference(dmp, 600, substeps=4), rtol=0, atol=1e-5)
    # ... and so reproduces the demonstration, start and end included
    assert rmse(out, points) < 1e-3  # cm (measured 5e-6 .. 3e-5)
    assert_array_equal(out[0], points[0])
    assert_allclose(out[-1], points[-1], atol=1e-3)


@pytest.mark.parametrize(
    ("stiffness", "damping", "alpha_x", "width_factor", "n_basis", "tau", "lam"), NON_DEFAULT
)
def test_non_default_constants_move_the_goal_by_their_own_transition(
    stiffness, damping, alpha_x, width_factor, n_basis, tau, lam
):
    points = word_like(400, loops=5)
    dmp = _fit_with(points, stiffness, damping, alpha_x, width_factor, n_basis, tau, lam)
    # s(t): the zero-weight DMP from 0 to 1 with the same constants, by RK4
    unit = DMP(
        weights=np.zeros((n_basis, 1)),
        y0=[0.0],
        goal=[1.0],
        tau=tau,
        stiffness=stiffness,
        damping=2.0 * math.sqrt(stiffness) if damping is None else damping,
        alpha_x=alpha_x,
        centres=dmp.centres,
        widths=dmp.widths,
        n_samples=400,
    )
    s = rk4_reference(unit, 400, substeps=4)[:, 0]
    shift = np.array([-1.2, 0.9])
    moved = rollout(dmp, goal=dmp.goal + shift)
    assert_allclose(moved - rollout(dmp), np.outer(s, shift), atol=1e-6)
    # and a new start: (y0_new - y0) (1 - s)
    start_shift = np.array([0.5, -2.0])
    restarted = rollout(dmp, y0=dmp.y0 + start_shift)
    assert_allclose(restarted - rollout(dmp), np.outer(1.0 - s, start_shift), atol=1e-6)


def test_basis_functions_use_a_non_default_width_factor_and_phase_constant():
    for n_basis, alpha_x, width_factor in [(7, 1.5, 2.5), (40, 5.0, 0.6)]:
        centres, widths = basis_functions(n_basis, alpha_x=alpha_x, width_factor=width_factor)
        want = np.exp(-alpha_x * np.linspace(0.0, 1.0, n_basis))
        assert_allclose(centres, want, rtol=1e-14)
        spacing = want[:-1] - want[1:]
        assert_allclose(widths, 1 / (2 * (width_factor * np.append(spacing, spacing[-1])) ** 2))
    # one basis function: the spacing 1 - exp(-alpha_x)
    centres, widths = basis_functions(1, alpha_x=2.0, width_factor=3.0)
    assert_array_equal(centres, [1.0])
    assert_allclose(widths, [1 / (2 * (3.0 * (1 - math.exp(-2.0))) ** 2)])


def test_phase_with_a_non_default_constant_is_the_closed_form():
    t = np.linspace(0.0, 2.5, 11)
    assert_allclose(dmp_module.phase(t, 2.5, alpha_x=0.7), np.exp(-0.7 * t / 2.5), rtol=1e-15)
    assert_allclose(dmp_module.phase(t, 2.5), np.exp(-math.log(100.0) * t / 2.5), rtol=1e-15)


# ----------------------------------------------------------------------------------------------
# Pieces that a correct fallback or a polynomial test path can hide


def test_the_banded_gram_matrix_is_the_band_of_the_dense_one():
    # a wrong band is not positive definite and the fit falls back to lstsq with the right
    # answer, so the fit's result alone cannot show it: compare the band itself
    for n, n_basis in [(300, 60), (1000, 200), (500, 26), (400, 25)]:
        x = np.exp(-dmp_module.ALPHA_X * np.linspace(0.0, 1.0, n))
        centres, widths = basis_functions(n_basis)
        start, values = dmp_module._design_band(x, centres, widths)
        width = values.shape[1]
        phi = dmp_module._dense(start, values, n_basis)
        banded = dmp_module._banded_gram(phi, start, width)
        gram = phi.T @ phi
        want = np.zeros((width, n_basis))
        for d in range(width):  # upper band storage: banded[width - 1 - d, i + d] = gram[i, i + d]
            want[width - 1 - d, d:] = np.diagonal(gram, d)
        assert_allclose(banded, want, rtol=1e-12, atol=1e-15 * np.abs(gram).max())


def test_a_gram_matrix_that_is_not_positive_definite_still_gives_the_ridge_solution():
    # more basis functions than samples and a vanishing ridge: Cholesky fails, lstsq takes over
    points = word_like(40, loops=2)
    lam = 1e-300
    dmp = fit_dmp(points, n_basis=120, regularisation=lam)
    phi = _design_for(dmp, 40)
    with pytest.raises(np.linalg.LinAlgError):
        np.linalg.cholesky(phi.T @ phi / 40 + lam * np.eye(120))
    _, targets = forcing_targets(points)
    expected = np.linalg.lstsq(phi, targets, rcond=None)[0]  # the minimum-norm solution
    assert_allclose(dmp.weights, expected, rtol=1e-6, atol=1e-9 * np.abs(expected).max())


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


def test_one_dimensional_and_one_basis_dmps_fit_store_and_restore():
    t = np.linspace(0.0, 1.0, 200)
    stroke = (10 * t**3 - 15 * t**4 + 6 * t**5)[:, None] * 4.0  # 1-D, from rest to rest
    dmp = fit_dmp(stroke)
    assert dmp.dims == 1 and dmp.tau == 1.0  # the documented default duration
    assert rmse(rollout(dmp), stroke) < 1e-3
    single = fit_dmp(stroke, n_basis=1)
    assert single.n_basis == 1 and single.widths[0] < 1.0
    for d in (dmp, single):
        restored = DMP.from_dict(json.loads(json.dumps(d.to_dict())))
        assert_array_equal(rollout(restored), rollout(d))
    two = DMP.from_dict({**single.to_dict(), "n_samples": 2})  # the fewest samples a rollout takes
    assert rollout(two).shape == (2, 1)


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("weights", [[np.nan]], "weights: expected finite"),
        ("weights", np.zeros((0, 1)), "weights: expected shape"),
        ("weights", np.zeros((2, 0)), "weights: expected shape"),
        ("centres", [1.0, 1.0], "centres: expected strictly decreasing"),
        ("centres", [0.5, 0.9], "centres: expected strictly decreasing"),
        ("widths", [1.0, 0.0], "widths: expected values > 0"),
        ("widths", [1.0], r"widths: expected shape \(2,\)"),
        ("y0", [0.0, 0.0], r"y0: expected shape \(1,\)"),
        ("goal", [np.inf], "goal: expected finite"),
        ("tau", 0.0, "tau: expected a number > 0"),
        ("stiffness", -1.0, "stiffness: expected a number > 0"),
        ("damping", -0.5, "damping: expected a number >= 0"),
        ("alpha_x", "fast", "alpha_x: expected a number"),
        ("n_samples", 1, "n_samples: expected an integer >= 2"),
    ],
)
def test_from_dict_names_every_bad_field(field, value, match):
    data = fit_dmp(word_like(50, loops=1)[:, :1], n_basis=2).to_dict()
    with pytest.raises(ValueError, match=match):
        DMP.from_dict({**data, field: value})


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


def test_basis_count_accepts_its_smallest_bounds_and_names_bad_ones():
    assert basis_count(1, per_100_points=10, minimum=1, maximum=1) == 1
    assert basis_count(3, per_100_points=10, minimum=1) == 1
    with pytest.raises(ValueError, match="n_points: expected an integer >= 1"):
        basis_count(0)
    with pytest.raises(ValueError, match="minimum: expected an integer >= 1"):
        basis_count(10, minimum=0)


def test_the_design_band_is_centred_on_each_samples_largest_activation():
    # the documented shortcut: 2 * _BAND + 1 columns around the nearest centre (a wrong band
    # would fall back to the dense matrix, which is right but not what is documented)
    band = dmp_module._BAND
    x = np.exp(-dmp_module.ALPHA_X * np.linspace(0.0, 1.0, 1500))
    for n_basis in (200, 500, 1000):  # (with 60 the columns outside are not negligible)
        centres, widths = basis_functions(n_basis)
        start, values = dmp_module._design_band(x, centres, widths)
        assert values.shape == (1500, 2 * band + 1)
        peak = design_matrix(x, centres, widths).argmax(axis=1)
        inner = (peak >= band) & (peak < n_basis - band)
        assert inner.mean() > 0.8
        assert_array_equal(start[inner] + band, peak[inner])
        assert np.all(start >= 0) and np.all(start + 2 * band + 1 <= n_basis)


def test_every_array_of_a_new_dmp_is_read_only():
    dmp = fit_dmp(word_like(60, loops=1), n_basis=5)
    for name in ("weights", "y0", "goal", "centres", "widths"):
        arr = getattr(dmp, name)
        assert arr.dtype == np.float64
        with pytest.raises(ValueError, match="read-only"):
            arr[0] = 1.0


def test_bad_basis_and_damping_values_are_named():
    with pytest.raises(ValueError, match="n_basis: expected an integer >= 1"):
        basis_functions(0)
    with pytest.raises(ValueError, match="alpha_x: expected a number > 0"):
        basis_functions(5, alpha_x=0.0)
    with pytest.raises(ValueError, match="damping: expected a finite number"):
        fit_dmp(word_like(50, loops=1), damping=np.nan)


# ----------------------------------------------------------------------------- moving ends


def moving_curve(n: int = 1000, tau: float = 2.0) -> np.ndarray:
    """A loopy 2-D curve (cm) that is already moving at its first sample and still at its last:
    constant drift plus loops, uniform in time over ``tau``."""
    t = np.linspace(0.0, tau, n)
    angle = 2 * np.pi * 3 * t / tau
    return np.column_stack([4.0 * t + 0.6 * np.sin(angle), 1.0 - np.cos(angle) + 0.5 * t])


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


def test_rollout_with_start_and_goal_velocities_matches_a_per_step_integration():
    dmp = fit_dmp(moving_curve(600), tau=1.5, n_basis=60, velocities="demonstrated")
    assert np.all(dmp.start_velocity != 0) and np.all(dmp.goal_velocity != 0)
    assert_allclose(rollout(dmp, 600), rk4_reference(dmp, 600, substeps=4), rtol=0, atol=1e-5)


def test_a_start_velocity_alone_gives_the_critically_damped_free_response():
    """Zero weights, goal at the start: only the start velocity moves the DMP, and the response
    of a critically damped spring to it is ``y0 + v0 t exp(-omega t)``, ``omega = sqrt(K) /
    tau``."""
    template = fit_dmp(np.zeros((50, 2)), tau=0.8, n_basis=10)
    v0 = np.array([3.0, -1.5])
    out = rollout(dataclasses_replace(template, weights=np.zeros((10, 2))), 401, start_velocity=v0)
    t = np.linspace(0.0, 0.8, 401)[:, None]
    omega = math.sqrt(template.stiffness) / 0.8
    assert_allclose(out, v0 * t * np.exp(-omega * t), rtol=0, atol=1e-9)


def dataclasses_replace(dmp: DMP, **changes) -> DMP:
    return DMP.from_dict(
        {**dmp.to_dict(), **{k: np.asarray(v).tolist() for k, v in changes.items()}}
    )


def test_rest_is_the_default_and_keeps_both_ends_at_rest(word):
    dmp = fit_dmp(moving_curve(), tau=2.0, n_basis=80)
    assert_array_equal(dmp.start_velocity, 0)
    assert_array_equal(dmp.goal_velocity, 0)
    out = rollout(dmp, 2001)
    step = 2.0 / 2000
    # starts at rest, unlike the path (9.7 cm/s): the first step only accelerates
    assert np.linalg.norm(out[1] - out[0]) / step < 0.01 * (4.0 + 0.6 * 3 * np.pi)
    # fitted at rest or with velocities, a word that starts and ends at rest is reproduced alike
    at_rest = rollout(fit_dmp(word, tau=3.0))
    demonstrated = rollout(fit_dmp(word, tau=3.0, velocities="demonstrated"))
    assert rmse(at_rest, demonstrated) < 1e-4


def test_velocities_round_trip_and_older_documents_load_at_rest():
    dmp = fit_dmp(moving_curve(300), tau=1.0, n_basis=40, velocities="demonstrated")
    restored = DMP.from_dict(json.loads(json.dumps(dmp.to_dict())))
    assert_array_equal(restored.start_velocity, dmp.start_velocity)
    assert_array_equal(rollout(restored), rollout(dmp))
    older = {k: v for k, v in dmp.to_dict().items() if k not in ("start_velocity", "goal_velocity")}
    assert_array_equal(DMP.from_dict(older).goal_velocity, [0.0, 0.0])
    with pytest.raises(UsageError, match=r"start_velocity: expected shape \(2,\)"):
        DMP.from_dict({**dmp.to_dict(), "start_velocity": [1.0]})


def test_bad_velocities_name_the_argument_and_what_is_accepted():
    with pytest.raises(UsageError, match="velocities: expected one of rest, demonstrated"):
        fit_dmp(moving_curve(100), velocities="measured")
    dmp = fit_dmp(moving_curve(100), n_basis=20)
    with pytest.raises(UsageError, match="goal_velocity: expected finite values"):
        rollout(dmp, goal_velocity=[np.nan, 0.0])


# ----------------------------------------------------------------------------- irregular times


def test_uniform_in_time_resamples_an_irregular_demonstration_for_the_fit():
    rng = np.random.default_rng(3)
    times = np.sort(rng.uniform(0.0, 2.0, 400))
    times = np.concatenate([[0.0], times, [2.0]])
    times[50] = times[49]  # two events in the same millisecond

    def path(t):
        return np.column_stack([4.0 * t + 0.6 * np.sin(3 * np.pi * t), 1.0 - np.cos(3 * np.pi * t)])

    uniform, duration = uniform_in_time(path(times), times, n_samples=500)
    assert duration == 2.0 and uniform.shape == (500, 2)
    assert rmse(uniform, path(np.linspace(0.0, 2.0, 500))) < 1e-3
    out = rollout(fit_dmp(uniform, tau=duration, n_basis=100, velocities="demonstrated"))
    assert rmse(out, path(np.linspace(0.0, 2.0, 500))) < 2e-3


@pytest.mark.parametrize(
    ("times", "message"),
    [
        ([0.0, 2.0, 1.0, 3.0], "times: expected non-decreasing values"),
        ([0.0, 0.0, 1.0, 1.0], "times: expected at least 3 distinct times"),
        ([0.0, 1.0, 2.0], r"times: expected shape \(4,\) like points"),
    ],
)
def test_uniform_in_time_refuses_times_it_cannot_resample(times, message):
    with pytest.raises(UsageError, match=message):
        uniform_in_time(np.zeros((4, 2)), times)
