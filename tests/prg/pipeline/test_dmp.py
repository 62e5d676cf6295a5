"""Tests of ``prg.pipeline.dmp`` (moved from the suite on: discrete DMP (prg.pipeline.dmp):
reproduction, generalisation, exactness of the rollout, fit)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from prg.errors import UsageError
from prg.pipeline import dmp as dmp_module
from prg.pipeline.dmp import (
    DMP,
    basis_functions,
    design_matrix,
    fit_dmp,
    forcing_targets,
    rollout,
)
from tests.helpers.dmp import (  # noqa: F401 (fixtures)
    moving_curve,
    rk4_reference,
    rmse,
    word,
    word_dmp,
    word_like,
)


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


def test_rollout_matches_rk4_with_new_start_goal_tempo_and_few_samples(word_dmp):
    # 300 samples for 200 basis functions: the rollout integrates on a finer grid
    kwargs = {"y0": [1.0, 2.0], "goal": [18.0, -1.0], "tau": 1.7}
    out = rollout(word_dmp, n_samples=300, **kwargs)
    assert_allclose(out, rk4_reference(word_dmp, 300, substeps=30, **kwargs), rtol=0, atol=5e-5)


def test_the_banded_design_matrix_equals_the_dense_one():
    x = np.exp(-dmp_module.ALPHA_X * np.linspace(-0.2, 1.2, 2001))
    for n_basis in (1, 3, 25, 26, 60, 75, 200, 500):
        centres, widths = basis_functions(n_basis)
        start, values = dmp_module._design_band(x, centres, widths)
        banded = dmp_module._dense(start, values, n_basis)
        assert_allclose(banded, design_matrix(x, centres, widths), rtol=0, atol=1e-15)


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


# ----------------------------------------------------------------------------- storage


def test_to_dict_from_dict_round_trip_through_json_gives_identical_rollouts(word_dmp):
    text = json.dumps(word_dmp.to_dict())
    restored = DMP.from_dict(json.loads(text))
    assert restored.n_basis == word_dmp.n_basis and restored.tau == word_dmp.tau
    assert_array_equal(rollout(restored), rollout(word_dmp))
    assert_array_equal(rollout(restored, goal=[3.0, 3.0]), rollout(word_dmp, goal=[3.0, 3.0]))


def test_from_dict_rejects_incomplete_or_inconsistent_data(word_dmp):
    data = word_dmp.to_dict()
    with pytest.raises(ValueError, match=r"missing keys \['widths'\]"):
        DMP.from_dict({k: v for k, v in data.items() if k != "widths"})
    with pytest.raises(ValueError, match=r"centres: expected shape"):
        DMP.from_dict({**data, "centres": data["centres"][:-1]})
    with pytest.raises(ValueError, match="n_basis"):
        DMP.from_dict({**data, "n_basis": 3})


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


def test_velocities_round_trip_and_older_documents_load_at_rest():
    dmp = fit_dmp(moving_curve(300), tau=1.0, n_basis=40, velocities="demonstrated")
    restored = DMP.from_dict(json.loads(json.dumps(dmp.to_dict())))
    assert_array_equal(restored.start_velocity, dmp.start_velocity)
    assert_array_equal(rollout(restored), rollout(dmp))
    older = {k: v for k, v in dmp.to_dict().items() if k not in ("start_velocity", "goal_velocity")}
    assert_array_equal(DMP.from_dict(older).goal_velocity, [0.0, 0.0])
    with pytest.raises(UsageError, match=r"start_velocity: expected shape \(2,\)"):
        DMP.from_dict({**dmp.to_dict(), "start_velocity": [1.0]})
