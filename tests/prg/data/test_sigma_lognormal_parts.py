"""Tests of the parts of ``prg.data.sigma_lognormal``, each against an independent reference.

What is compared with what:

- params: the documented constants and the ``(k, 6)`` float layout.
- model: ``_lognormal_terms`` against ``scipy.stats.norm``; ``component_speeds`` against
  ``scipy.stats.lognorm`` (the speed of a component is ``D`` times a lognormal density);
  ``velocity`` and ``speed`` against the direction law written out by hand; ``trajectory`` against
  ``scipy.integrate.cumulative_trapezoid`` of the velocity on a fine grid; the Jacobians of
  ``_displacements`` and ``_component_velocities`` against central finite differences, and the
  sweep derivative against ``mpmath.quad`` of its defining integral.
- solver: ``_solve_spd`` against ``numpy.linalg.solve``; ``_levenberg_marquardt`` against
  ``numpy.linalg.lstsq``, ``scipy.optimize.least_squares``, Marquardt steps computed by hand with
  ``numpy.linalg.solve``, and counted evaluations.
- fitting: the parametrisation and bounds against hand values and finite differences; the
  refinements against known strokes; ``fit`` against its documented procedure composed of the
  (separately tested) steps, its messages against hand-made inputs.
- extraction: ``_crossing`` and ``_init_component`` on hand-made speed profiles whose
  half-maximum points are known exactly, and on a finely sampled exact lognormal.
- timing: ``power_law_timestamps`` against hand-computed small cases and a loop-by-loop
  reference of the documented law.
- snr and perturbation: hand cases and the same draws made by hand with numpy.
"""

from __future__ import annotations

import itertools
import math

import mpmath
import numpy as np
import pytest
from scipy import integrate, optimize
from scipy.ndimage import gaussian_filter1d
from scipy.stats import lognorm, norm

from prg.data import sigma_lognormal as sl

# Two components with distinct angles; the second starts inside the grids below, so part of
# it is inactive.
TWO = np.array(
    [
        [1.3, 0.05, -1.4, 0.3, 0.7, 2.2],
        [0.8, 0.4537, -1.1, 0.4, -0.5, -1.6],
    ]
)

# A three-component stroke (the suite's known stroke) for the refinements and the fit.
THREE = np.array(
    [
        [1.0, -0.05, -1.6, 0.3, 0.3, 1.2],
        [1.2, 0.15, -1.3, 0.25, 2.5, 3.5],
        [0.8, 0.40, -1.2, 0.3, -1.0, -2.4],
    ]
)

H = math.sqrt(2.0 * math.log(2.0))  # half-maximum offset in log time, in units of sigma


def _expected_speeds(params: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``v_i(t) = D_i * lognormal density of t - t0_i`` (scipy), zero before ``t0_i``."""
    out = np.zeros((params.shape[0], t.shape[0]))
    for i, (d, t0, mu, sigma, _, _) in enumerate(params):
        out[i] = d * lognorm.pdf(t - t0, s=sigma, scale=math.exp(mu))
    return out


def _expected_directions(params: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``phi_i(t) = theta_s + (theta_e - theta_s) Phi(z)`` (scipy), ``theta_s`` before ``t0``."""
    out = np.zeros((params.shape[0], t.shape[0]))
    for i, (_, t0, mu, sigma, ths, the) in enumerate(params):
        tau = t - t0
        cdf = np.zeros_like(t)
        on = tau > 0
        cdf[on] = norm.cdf((np.log(tau[on]) - mu) / sigma)
        out[i] = ths + (the - ths) * cdf
    return out


def _expected_velocity(params: np.ndarray, t: np.ndarray) -> np.ndarray:
    v = _expected_speeds(params, t)
    phi = _expected_directions(params, t)
    return np.column_stack([(v * np.cos(phi)).sum(0), (v * np.sin(phi)).sum(0)])


# ----------------------------------------------------------------------------------------------
# params
# ----------------------------------------------------------------------------------------------


def test_parameter_columns_and_bounds_have_the_documented_values():
    assert (sl.D, sl.T0, sl.MU, sl.SIGMA, sl.THETA_S, sl.THETA_E) == (0, 1, 2, 3, 4, 5)
    assert sl.N_PARAMS == 6
    assert sl.SIGMA_BOUNDS == (0.05, 1.5)
    assert sl.MU_MAX == 3.0
    assert sl.MIN_WIDTH == 1.0
    np.testing.assert_equal(sl.MAX_SWEEP, math.pi)
    assert sl.MAX_AMPLITUDE == 2.0
    assert sl._TINY == 1e-12


def test_as_params_reshapes_to_float_rows_of_six():
    flat = list(range(12))  # integers: the result is float64 all the same
    p = sl._as_params(flat)
    assert p.dtype == np.float64 and p.shape == (2, 6)
    np.testing.assert_array_equal(p, np.arange(12.0).reshape(2, 6))
    one = sl._as_params(np.arange(6))
    assert one.shape == (1, 6) and one.dtype == np.float64
    three = sl._as_params(np.ones((3, 6)))
    assert three.shape == (3, 6)
    empty = sl._empty_params()
    assert empty.shape == (0, 6) and empty.dtype == np.float64


# ----------------------------------------------------------------------------------------------
# model
# ----------------------------------------------------------------------------------------------


def test_lognormal_terms_agree_with_scipy_norm_and_are_zero_when_inactive():
    params = np.array([[1.0, 0.0, -1.0, 0.3, 0.0, 1.0], [2.0, 0.35, -0.5, 0.6, 1.0, -1.0]])
    # times before, at, within _TINY of, and just beyond _TINY after each t0
    t = np.array([-0.5, 0.0, 1e-12, 2e-12, 0.01, 0.2, 0.35, 0.351, 0.5, 0.9, 1.7, 3.0])
    tau, active, z, cdf, pdf = sl._lognormal_terms(params, t)
    for arr in (tau, active, z, cdf, pdf):
        assert arr.shape == (2, t.shape[0])
    raw = t[None, :] - params[:, 1, None]
    expect_active = raw > 1e-12  # t0 + 1e-12 itself is still at rest
    np.testing.assert_array_equal(active, expect_active)
    assert not active[0, 2] and active[0, 3]
    np.testing.assert_allclose(tau[active], raw[active], rtol=1e-15)
    assert np.all(np.isfinite(np.log(tau[~active])))  # a positive placeholder: no log of <= 0
    expect_z = (np.log(np.where(active, raw, 1.0)) - params[:, 2, None]) / params[:, 3, None]
    np.testing.assert_allclose(z[active], expect_z[active], rtol=1e-13)
    assert np.all(z[~active] == -np.inf)
    np.testing.assert_allclose(cdf[active], norm.cdf(expect_z[active]), rtol=1e-12, atol=1e-300)
    np.testing.assert_allclose(pdf[active], norm.pdf(expect_z[active]), rtol=1e-12, atol=1e-300)
    assert np.all(cdf[~active] == 0.0) and np.all(pdf[~active] == 0.0)
    # a one-dimensional parameter vector is one component
    single = sl._lognormal_terms(params[1], t)[3]
    np.testing.assert_array_equal(single, cdf[1:2])


def test_component_speeds_are_scaled_lognormal_densities():
    t = np.linspace(-0.2, 1.5, 171)
    got = sl.component_speeds(TWO, t)
    assert got.shape == (2, t.shape[0])
    np.testing.assert_allclose(got, _expected_speeds(TWO, t), rtol=1e-12, atol=1e-300)
    assert np.all(got[1, t <= TWO[1, sl.T0]] == 0.0)
    # a list of times works like an array
    np.testing.assert_allclose(sl.component_speeds(TWO, list(t[:5])), got[:, :5])


def test_velocity_and_speed_are_the_vector_sum_of_the_components():
    t = np.linspace(-0.2, 1.5, 171)
    vel = sl.velocity(TWO, t)
    assert vel.shape == (t.shape[0], 2)
    expect = _expected_velocity(TWO, t)
    np.testing.assert_allclose(vel, expect, rtol=1e-11, atol=1e-13)
    sp = sl.speed(TWO, t)
    assert sp.shape == (t.shape[0],)
    np.testing.assert_allclose(sp, np.hypot(expect[:, 0], expect[:, 1]), rtol=1e-11, atol=1e-13)


def test_trajectory_integrates_the_velocity_from_the_start_point():
    t = np.linspace(-0.1, 2.0, 40001)
    vel = _expected_velocity(TWO, t)
    integral = np.column_stack(
        [integrate.cumulative_trapezoid(vel[:, i], t, initial=0.0) for i in range(2)]
    )
    start = [0.25, -1.5]
    traj = sl.trajectory(TWO, t, start)
    assert traj.shape == (t.shape[0], 2)
    np.testing.assert_allclose(traj, integral + np.array(start), atol=2e-6)
    np.testing.assert_allclose(sl.trajectory(TWO, t), integral, atol=2e-6)  # default: origin
    # each component alone ends (Phi = 1) at D times the unit chord of its sweep
    for comp in TWO:
        d, ths, the = comp[sl.D], comp[sl.THETA_S], comp[sl.THETA_E]
        chord = d * np.array([math.sin(the) - math.sin(ths), math.cos(ths) - math.cos(the)])
        end = sl.trajectory(comp, np.array([1e4]))[0]
        np.testing.assert_allclose(end, chord / (the - ths), rtol=1e-9)


def test_displacements_of_each_component_and_their_absent_jacobian():
    t = np.linspace(-0.1, 2.0, 20001)
    disp, jac = sl._displacements(TWO, t, with_jacobian=False)
    assert jac is None
    assert disp.shape == (2, t.shape[0]) and np.iscomplexobj(disp)
    speeds = _expected_speeds(TWO, t)
    phi = _expected_directions(TWO, t)
    for i in range(2):
        vi = speeds[i] * np.exp(1j * phi[i])
        ref = integrate.cumulative_trapezoid(vi, t, initial=0.0)
        np.testing.assert_allclose(disp[i], ref, atol=5e-6)


def _central_differences(func, params: np.ndarray, t: np.ndarray, h: float) -> np.ndarray:
    """Derivatives (6, k, n) of ``func(params, t)`` (k, n) in D, t0, mu, sigma, theta_s (sweep
    held fixed: theta_e moves with it) and the sweep delta = theta_e - theta_s."""
    k = params.shape[0]
    out = np.zeros((6, k, t.shape[0]), dtype=complex)
    for i in range(k):
        for j in range(6):
            step = np.zeros_like(params)
            step[i, j] = h
            if j == sl.THETA_S:
                step[i, sl.THETA_E] = h
            up, down = func(params + step, t), func(params - step, t)
            out[j, i] = (up[i] - down[i]) / (2 * h)
    return out


def _assert_jacobian(jac: np.ndarray, fd: np.ndarray, rtol: float = 1e-6) -> None:
    for j in range(6):
        scale = np.abs(fd[j]).max()
        np.testing.assert_allclose(jac[j], fd[j], rtol=rtol, atol=rtol * scale + 1e-12)


@pytest.mark.parametrize("sweep", [1.5, -1.1, 5e-4, -8e-4, 0.0])
def test_displacement_jacobian_matches_central_differences(sweep):
    params = TWO.copy()
    params[1, sl.THETA_E] = params[1, sl.THETA_S] + sweep
    t = np.linspace(0.0, 1.2, 97)  # the second component is at rest on part of the grid
    disp, jac = sl._displacements(params, t, with_jacobian=True)
    assert jac.shape == (6, 2, t.shape[0]) and jac.dtype == np.complex128

    def value(p, tt):
        return sl._displacements(p, tt, with_jacobian=False)[0]

    np.testing.assert_array_equal(disp, value(params, t))
    _assert_jacobian(jac, _central_differences(value, params, t, 1e-6))
    assert np.all(jac[:, 1, t <= params[1, sl.T0]] == 0.0)


def _sweep_integral(cdf: float, delta: float) -> complex:
    """``F = int_0^Phi i u exp(i delta u) du`` by quadrature in 30-digit arithmetic."""
    with mpmath.workdps(30):
        value = mpmath.quad(lambda u: 1j * u * mpmath.exp(1j * delta * u), [0, cdf])
    return complex(value)


@pytest.mark.parametrize("delta", [0.0, 5e-4, -9.99e-4, 1e-3, 0.3, -2.0])
def test_sweep_derivative_is_its_defining_integral(delta):
    # D = 1, theta_s = 0: the derivative in the sweep is F itself; t0 = 0, mu = 0, sigma = 1
    # puts Phi = norm.cdf(log t).
    phis = np.array([0.05, 0.3, 0.7, 0.95, 0.9999])
    t = np.exp(norm.ppf(phis))
    params = np.array([[1.0, 0.0, 0.0, 1.0, 0.0, delta]])
    _, jac = sl._displacements(params, t, with_jacobian=True)
    expect = np.array([_sweep_integral(p, delta) for p in norm.cdf(np.log(t))])
    # below |delta| = 1e-3 a series truncated after delta^2 is used: error below |delta|^3 / 30
    tol = 4e-12 if abs(delta) >= 1e-3 else abs(delta) ** 3 / 25 + 4e-12
    np.testing.assert_allclose(jac[sl.THETA_E, 0], expect, rtol=0, atol=tol)


@pytest.mark.parametrize("sweep", [1.5, -0.7, 0.0])
def test_component_velocity_jacobian_matches_central_differences(sweep):
    params = TWO.copy()
    params[0, sl.THETA_E] = params[0, sl.THETA_S] + sweep
    t = np.linspace(0.0, 1.2, 97)
    vel, jac = sl._component_velocities(params, t)
    assert vel.shape == (2, t.shape[0]) and jac.shape == (6, 2, t.shape[0])
    assert jac.dtype == np.complex128
    expect = _expected_speeds(params, t) * np.exp(1j * _expected_directions(params, t))
    np.testing.assert_allclose(vel, expect, rtol=1e-11, atol=1e-13)

    def value(p, tt):
        return sl._component_velocities(p, tt)[0]

    _assert_jacobian(jac, _central_differences(value, params, t, 1e-6), rtol=2e-6)
    assert np.all(jac[:, 1, t <= params[1, sl.T0]] == 0.0)


# ----------------------------------------------------------------------------------------------
# snr
# ----------------------------------------------------------------------------------------------


def test_snr_of_hand_made_reconstructions():
    x = np.array([[0.0, 1.0], [2.0, 1.0], [0.0, 5.0], [2.0, 5.0]])  # x and y means differ
    signal = 4 * (1.0 + 4.0)  # each point at (+-1, +-2) from the mean (1, 3)
    assert sl.snr_db(x, x) == 200.0  # perfect: capped
    noisy = x + np.array([[0.1, 0.0], [0.0, -0.2], [0.0, 0.0], [0.3, 0.0]])
    noise = 0.01 + 0.04 + 0.09
    assert sl.snr_db(x, noisy) == pytest.approx(10 * math.log10(signal / noise), rel=1e-12)
    # a worse reconstruction than the mean: negative dB
    far = x + 3.0
    assert sl.snr_db(x, far) == pytest.approx(10 * math.log10(signal / (8 * 9.0)), rel=1e-12)
    # small strokes are not special: 0.01 of the extent, same ratio
    small = 0.01 * x
    assert sl.snr_db(small, 0.01 * noisy) == pytest.approx(sl.snr_db(x, noisy), rel=1e-9)
    # a noise below 1e-20 of the signal counts as 1e-20 of it: 200 dB
    assert sl.snr_db(x, x + 1e-12) == pytest.approx(200.0)
    assert sl.snr_db(x, x + 1e-9) == pytest.approx(10 * math.log10(signal / (8 * 1e-18)))


def test_snr_of_a_stroke_without_extent_is_zero():
    still = np.full((5, 2), 0.7)
    assert sl.snr_db(still, still) == 0.0
    assert sl.snr_db(still, still + 1.0) == 0.0


# ----------------------------------------------------------------------------------------------
# perturbation
# ----------------------------------------------------------------------------------------------


def _perturb_by_hand(params, seed, amplitude, rotation_deg, sweep):
    rng = np.random.default_rng(seed)
    k = params.shape[0]
    rot = math.radians(rotation_deg)
    scale = rng.uniform(1 - amplitude, 1 + amplitude, size=k)
    rotation = rng.uniform(-rot, rot, size=k)
    jitter = rng.uniform(-sweep, sweep, size=(k, 2))
    out = params.copy()
    sweep_angle = params[:, 5] - params[:, 4]
    out[:, 0] = params[:, 0] * scale
    out[:, 4] = params[:, 4] + rotation + jitter[:, 0] * sweep_angle
    out[:, 5] = params[:, 5] + rotation + jitter[:, 1] * sweep_angle
    return out


def test_perturb_makes_the_documented_draws_in_order():
    params = TWO.copy()
    before = params.copy()
    got = sl.perturb(params, np.random.default_rng(42), 0.3, 12.0, 0.2)
    np.testing.assert_allclose(got, _perturb_by_hand(params, 42, 0.3, 12.0, 0.2), rtol=1e-14)
    np.testing.assert_array_equal(params, before)  # the input is not modified
    assert got is not params


def test_perturb_defaults_are_a_tenth_five_degrees_and_five_hundredths():
    three = np.vstack([TWO, [[0.5, 0.6, -1.0, 0.2, 2.0, 0.5]]])
    got = sl.perturb(three, np.random.default_rng(7))
    np.testing.assert_allclose(got, _perturb_by_hand(three, 7, 0.1, 5.0, 0.05), rtol=1e-14)


def test_perturb_accepts_a_flat_parameter_vector():
    got = sl.perturb(TWO[0], np.random.default_rng(3), 0.2, 10.0, 0.1)
    assert got.shape == (1, 6)
    np.testing.assert_allclose(got, _perturb_by_hand(TWO[:1], 3, 0.2, 10.0, 0.1), rtol=1e-14)


# ----------------------------------------------------------------------------------------------
# solver
# ----------------------------------------------------------------------------------------------


def test_sum_squares_of_hand_vectors():
    assert sl._sum_squares(np.array([3.0, 4.0])) == 25.0
    assert sl._sum_squares(np.array([-1.5, 2.0, 0.5])) == 6.5
    x = np.random.default_rng(0).normal(size=50)
    assert sl._sum_squares(x) == pytest.approx(float(np.sum(x**2)), rel=1e-13)


def _spd(n: int, seed: int, scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    jac = rng.normal(size=(2 * n + 3, n))
    return scale * (jac.T @ jac + 0.1 * np.eye(n)), rng.normal(size=n)


@pytest.mark.parametrize("n", [1, 2, 3, 5, 8, 23, 24, 25, 26, 40])
def test_spd_solve_agrees_with_numpy(n):
    a, b = _spd(n, 100 + n)
    np.testing.assert_allclose(sl._solve_spd(a, b), np.linalg.solve(a, b), rtol=1e-9, atol=1e-12)
    # pivots far below one are fine too
    small, _ = _spd(n, 200 + n, scale=1e-4)
    np.testing.assert_allclose(
        sl._solve_spd(small, b), np.linalg.solve(small, b), rtol=1e-9, atol=1e-12
    )


@pytest.mark.parametrize("n", [3, 30])
def test_spd_solve_accepts_integer_arrays(n):
    rng = np.random.default_rng(n)
    m = rng.integers(-3, 4, size=(n + 2, n))
    a = m.T @ m + 2 * np.eye(n, dtype=int)  # integer and positive definite
    b = rng.integers(-5, 6, size=n)
    assert a.dtype.kind == "i" and b.dtype.kind == "i"
    np.testing.assert_allclose(sl._solve_spd(a, b), np.linalg.solve(a, b), rtol=1e-9, atol=1e-12)


def test_spd_solve_up_to_24_unknowns_takes_the_plain_python_path():
    a, b = _spd(24, 7)
    np.testing.assert_array_equal(sl._solve_spd(a, b), sl._solve_spd_small(a.tolist(), b.tolist()))
    a, b = _spd(6, 8)
    x = sl._solve_spd_small(a.tolist(), b.tolist())
    assert isinstance(x, np.ndarray) and x.shape == (6,)
    np.testing.assert_allclose(x, np.linalg.solve(a, b), rtol=1e-10)


def _not_positive_definite(n: int, where: str) -> np.ndarray:
    a, _ = _spd(n, 300 + n)
    if where == "first zero":
        a[0, :] = a[:, 0] = 0.0
    elif where == "first negative":
        a[0, 0] = -1.0
    elif where == "later zero":  # an all-ones 2 x 2 block at the end: an exact zero pivot
        a = np.eye(n)
        a[-2:, -2:] = 1.0
    else:  # "later negative"
        a[-1, -1] = -abs(a[-1, -1])
    return a


@pytest.mark.parametrize("n", [2, 3, 24, 30])
@pytest.mark.parametrize("where", ["first zero", "first negative", "later zero", "later negative"])
def test_spd_solve_refuses_a_matrix_that_is_not_positive_definite(n, where):
    a = _not_positive_definite(n, where)
    with pytest.raises(np.linalg.LinAlgError):
        sl._solve_spd(a, np.ones(n))


class _Counted:
    """A residual function that counts its evaluations."""

    def __init__(self, func):
        self.func = func
        self.calls = 0
        self.points = []

    def __call__(self, x):
        self.calls += 1
        self.points.append(np.array(x, dtype=float))
        return self.func(x)


def _linear(a: np.ndarray, b: np.ndarray):
    return lambda x: (a @ x - b, a.copy())


def _marquardt_step(a, b, x, lam):
    """One damped Gauss-Newton step on ``a x - b`` with Marquardt's scaled damping."""
    res = a @ x - b
    normal = a.T @ a
    diag = np.diag(normal)
    scale = np.maximum(diag, 1e-6 * diag.max() + 1e-30)
    return x + np.linalg.solve(normal + lam * np.diag(scale), -(a.T @ res))


def test_levenberg_marquardt_solves_a_linear_least_squares_problem():
    rng = np.random.default_rng(1)
    a = rng.normal(size=(12, 4))
    b = rng.normal(size=12)
    inf = np.full(4, np.inf)
    x = sl._levenberg_marquardt(_linear(a, b), np.zeros(4), -inf, inf, max_nfev=50)
    # it stops once a step gains less than 1e-6 of the cost: close, not exact
    np.testing.assert_allclose(x, np.linalg.lstsq(a, b, rcond=None)[0], rtol=2e-5, atol=1e-6)


def test_levenberg_marquardt_takes_marquardt_steps_from_a_damping_of_1e_minus_3():
    # An ill-conditioned linear problem, so the damping shows in every step; the first step
    # is taken with lambda = 1e-3, each accepted step divides it by 3.
    a = np.array([[1.0, 0.0, 0.0], [0.0, 0.03, 0.0], [0.0, 0.0, 0.002], [1.0, 1.0, 1.0]])
    a = a * np.array([5.0, 1.0, 1.0])  # unequal column norms: the scaling matters
    b = np.array([1.0, -2.0, 0.5, 0.3])
    x0 = np.array([0.4, 0.2, -0.3])
    inf = np.full(3, np.inf)
    x = x0.copy()
    lam = 1e-3
    for nfev in (2, 3, 4):
        x = _marquardt_step(a, b, x, lam)
        lam /= 3.0
        got = sl._levenberg_marquardt(_linear(a, b), x0, -inf, inf, max_nfev=nfev)
        np.testing.assert_allclose(got, x, rtol=1e-11, atol=1e-14)
    # the scaling floor: a column 1e-8 as large as the others is damped by 1e-6 of the largest
    a2 = np.array([[10.0, 0.0], [0.0, 1e-7], [1.0, 1e-7]])
    b2 = np.array([1.0, 1.0, 0.0])
    got = sl._levenberg_marquardt(_linear(a2, b2), np.zeros(2), -inf[:2], inf[:2], max_nfev=2)
    np.testing.assert_allclose(got, _marquardt_step(a2, b2, np.zeros(2), 1e-3), rtol=1e-11)


def test_levenberg_marquardt_damping_falls_by_three_to_a_floor_of_1e_minus_9():
    # nearly parallel columns and an exact solution: every step is accepted, the damping
    # matters for all of them; the 14th step is the first at the floor
    a = np.array([[1.0, 0.999], [0.999, 1.0]])
    b = a @ np.array([1.0, 2.0])
    inf = np.full(2, np.inf)
    f = _Counted(_linear(a, b))
    got = sl._levenberg_marquardt(f, np.array([5.0, -7.0]), -inf, inf, max_nfev=15)
    assert f.calls == 15
    lams = [max(1e-3 / 3.0**i, 1e-9) for i in range(14)]
    assert lams[12] > 1e-9 and lams[13] == 1e-9
    x = np.array([5.0, -7.0])
    for point, lam in zip(f.points[1:], lams):
        x = _marquardt_step(a, b, x, lam)
        np.testing.assert_allclose(point, x, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(got, f.points[-1])
    np.testing.assert_allclose(got, [1.0, 2.0], atol=1e-6)


def test_levenberg_marquardt_fits_a_nonlinear_curve_like_scipy():
    rng = np.random.default_rng(5)
    t = np.linspace(0.0, 3.0, 30)
    y = 2.0 * np.exp(-1.3 * t) + 0.4 + rng.normal(0, 0.01, t.shape)

    def residual(x):
        return x[0] * np.exp(-x[1] * t) + x[2] - y

    def evaluate(x):
        e = np.exp(-x[1] * t)
        return residual(x), np.column_stack([e, -x[0] * t * e, np.ones_like(t)])

    x0 = np.array([1.0, 0.5, 0.0])
    inf = np.full(3, np.inf)
    got = sl._levenberg_marquardt(evaluate, x0, -inf, inf, max_nfev=100)
    ref = optimize.least_squares(residual, x0, xtol=1e-14, ftol=1e-14, gtol=1e-14).x
    np.testing.assert_allclose(got, ref, rtol=1e-5)


def test_levenberg_marquardt_stops_at_an_active_bound_on_the_clipped_solution():
    # separable: the constrained minimiser is the clipped unconstrained one
    a = np.diag([1.0, 2.0, 0.5])
    b = np.array([3.0, -4.0, 0.25])  # unconstrained solution (3, -2, 0.5)
    lo = np.array([-1.0, -1.0, -1.0])
    hi = np.array([1.0, 1.0, 1.0])
    x = sl._levenberg_marquardt(_linear(a, b), np.zeros(3), lo, hi, max_nfev=60)
    np.testing.assert_allclose(x, [1.0, -1.0, 0.5], rtol=0, atol=1e-6)
    assert x[0] == 1.0 and x[1] == -1.0  # exactly on the bounds
    ref = optimize.least_squares(lambda x: a @ x - b, np.zeros(3), bounds=(lo, hi)).x
    np.testing.assert_allclose(x, ref, atol=1e-6)


def _rosenbrock(x):
    return np.array([10.0 * (x[1] - x[0] ** 2), 1.0 - x[0]]), np.array(
        [[-20.0 * x[0], 10.0], [-1.0, 0.0]]
    )


def test_levenberg_marquardt_makes_at_most_max_nfev_evaluations_and_never_increases_cost():
    x0 = np.array([-1.2, 1.0])
    inf = np.full(2, np.inf)
    costs = []
    for max_nfev in range(1, 12):
        f = _Counted(_rosenbrock)
        x = sl._levenberg_marquardt(f, x0, -inf, inf, max_nfev=max_nfev)
        assert f.calls == max_nfev  # far from converged: every evaluation is used
        costs.append(float(np.sum(_rosenbrock(x)[0] ** 2)))
        if max_nfev == 1:
            np.testing.assert_array_equal(x, x0)
    assert costs[0] == pytest.approx(24.2)
    assert all(later <= earlier for earlier, later in itertools.pairwise(costs))
    assert costs[-1] < costs[0]
    f = _Counted(_rosenbrock)
    x = sl._levenberg_marquardt(f, x0, -inf, inf, max_nfev=200)
    np.testing.assert_allclose(x, [1.0, 1.0], atol=1e-5)


def test_levenberg_marquardt_stops_once_the_cost_reaches_stop_cost():
    a = np.array([[1.0, 0.2], [0.0, 0.01], [0.3, 1.0]])
    b = np.array([1.0, 2.0, -1.0])
    x0 = np.array([4.0, -3.0])
    inf = np.full(2, np.inf)
    minimum = float(np.sum((a @ np.linalg.lstsq(a, b, rcond=None)[0] - b) ** 2))
    # the points visited when nothing stops the solver early
    free = _Counted(_linear(a, b))
    sl._levenberg_marquardt(free, x0, -inf, inf, max_nfev=12, stop_cost=0.0)
    costs = [float(np.sum((a @ p - b) ** 2)) for p in free.points]
    assert costs[0] > costs[1] > costs[2] > costs[3] > minimum
    stop = 0.5 * (costs[1] + costs[2])  # reached at the third evaluation
    f = _Counted(_linear(a, b))
    x = sl._levenberg_marquardt(f, x0, -inf, inf, max_nfev=12, stop_cost=stop)
    assert f.calls == 3
    np.testing.assert_array_equal(x, free.points[2])
    # a cost already at stop_cost: no step at all
    f = _Counted(_linear(a, b))
    x = sl._levenberg_marquardt(f, x0, -inf, inf, max_nfev=12, stop_cost=costs[0])
    assert f.calls == 1
    np.testing.assert_array_equal(x, x0)


def test_levenberg_marquardt_default_stop_cost_is_zero():
    a = np.eye(2)
    b = np.array([0.3, -0.2])
    inf = np.full(2, np.inf)
    f = _Counted(_linear(a, b))
    x = sl._levenberg_marquardt(f, np.zeros(2), -inf, inf, 5)  # cost 0.13 at the start
    assert f.calls > 1
    np.testing.assert_allclose(x, b, rtol=1e-6)
    # an exact solution (cost 0) at the start: nothing to do
    f = _Counted(_linear(a, b))
    x = sl._levenberg_marquardt(f, b.copy(), -inf, inf, 50)
    assert f.calls == 1
    np.testing.assert_array_equal(x, b)


def test_levenberg_marquardt_stalls_when_the_relative_gain_is_below_1e_minus_6():
    # the residual has a fixed part of 1e4: removing the variable part (cost 1) gains 1e-8 of
    # the cost, so the solver stops after one accepted step
    def evaluate(x):
        return np.array([x[0] - 1.0, 1e4]), np.array([[1.0], [0.0]])

    f = _Counted(evaluate)
    x = sl._levenberg_marquardt(f, np.zeros(1), np.full(1, -np.inf), np.full(1, np.inf), 50)
    assert f.calls == 2
    assert x[0] == pytest.approx(1.0 / (1.0 + 1e-3), rel=1e-12)
    # a relative gain above 1e-6: it goes on
    f = _Counted(_linear(np.eye(1), np.ones(1)))
    sl._levenberg_marquardt(f, np.zeros(1), np.full(1, -np.inf), np.full(1, np.inf), 50)
    assert f.calls > 2


def test_levenberg_marquardt_rejects_steps_that_do_not_lower_the_cost():
    # a Jacobian of the wrong sign: every step goes uphill; the damping grows by 4 from 1e-3
    # while below 1e8 (19 tries), then the start is returned
    def evaluate(x):
        return x - 1.0, -np.eye(1)

    inf = np.full(1, np.inf)
    f = _Counted(evaluate)
    x = sl._levenberg_marquardt(f, np.zeros(1), -inf, inf, max_nfev=100)
    assert f.calls == 20
    np.testing.assert_array_equal(x, [0.0])
    lam = 1e-3 * 4.0 ** np.arange(19)
    np.testing.assert_allclose(np.concatenate(f.points[1:]), -1.0 / (1.0 + lam), rtol=1e-12)
    f = _Counted(evaluate)
    sl._levenberg_marquardt(f, np.zeros(1), -inf, inf, max_nfev=7)
    assert f.calls == 7
    # a zero Jacobian: the step is zero, the cost equal, not lower: rejected the same way
    f = _Counted(lambda x: (np.array([x[0] - 2.0, 1.0]), np.zeros((2, 1))))
    x = sl._levenberg_marquardt(f, np.full(1, 0.5), -inf, inf, max_nfev=100)
    assert f.calls == 20
    np.testing.assert_array_equal(x, [0.5])


def test_levenberg_marquardt_gives_up_on_a_jacobian_that_is_not_finite():
    f = _Counted(lambda x: (x - 1.0, np.full((2, 2), np.nan)))
    inf = np.full(2, np.inf)
    x = sl._levenberg_marquardt(f, np.zeros(2), -inf, inf, max_nfev=100)
    assert f.calls == 1
    np.testing.assert_array_equal(x, [0.0, 0.0])


def test_levenberg_marquardt_rejects_a_step_to_a_non_finite_residual():
    # the residual is not finite beyond x = 0.5; the full step would land at 1
    def evaluate(x):
        res = x - 1.0 if x[0] <= 0.5 else np.full(1, np.nan)
        return res, np.eye(1)

    f = _Counted(evaluate)
    x = sl._levenberg_marquardt(f, np.zeros(1), np.full(1, -np.inf), np.full(1, np.inf), 30)
    assert f.points[1][0] > 0.5  # tried, and rejected
    assert 0.0 < x[0] <= 0.5  # a finite residual, lower than at the start


def test_levenberg_marquardt_returns_the_clipped_start_when_the_first_residual_is_not_finite():
    f = _Counted(lambda x: (np.full(3, np.inf), np.eye(3)))
    lo, hi = np.array([0.0, -1.0, 2.0]), np.array([1.0, 1.0, 3.0])
    x = sl._levenberg_marquardt(f, np.array([5.0, 0.5, -4.0]), lo, hi, max_nfev=10)
    assert f.calls == 1
    np.testing.assert_array_equal(x, [1.0, 0.5, 2.0])
    np.testing.assert_array_equal(f.points[0], [1.0, 0.5, 2.0])  # evaluated at the clipped start


# ----------------------------------------------------------------------------------------------
# timing
# ----------------------------------------------------------------------------------------------


def _timestamps_by_hand(
    points, total_time=1.0, smooth=2.0, curvature_range=(2.0, 60.0), ramp=0.1, ramp_floor=0.3
):
    """The two-thirds power law, vertex by vertex (the module docstring)."""
    pts = [(float(x), float(y)) for x, y in points]
    n = len(pts)
    ds = [math.dist(pts[i], pts[i + 1]) for i in range(n - 1)]
    length = sum(ds)
    # turning angle per unit arc length (the mean of the two segments), times the length
    kappa = [0.0] * n
    for i in range(1, n - 1):
        h1 = math.atan2(pts[i][1] - pts[i - 1][1], pts[i][0] - pts[i - 1][0])
        h2 = math.atan2(pts[i + 1][1] - pts[i][1], pts[i + 1][0] - pts[i][0])
        turn = abs(math.remainder(h2 - h1, 2 * math.pi))
        kappa[i] = turn / max(0.5 * (ds[i - 1] + ds[i]), 1e-12 * length) * length
    kappa[0], kappa[-1] = kappa[1], kappa[-2]  # the end points have no turn of their own
    kappa = np.array(kappa)
    if smooth > 0:
        kappa = gaussian_filter1d(kappa, smooth, mode="nearest")
    speed = []
    arc = 0.0
    for i in range(n):
        v = min(max(kappa[i], curvature_range[0]), curvature_range[1]) ** (-1.0 / 3.0)
        if ramp > 0:
            s = arc / length
            e = min(max(min(s, 1.0 - s) / ramp, 0.0), 1.0)
            v *= ramp_floor + (1.0 - ramp_floor) * (3 * e**2 - 2 * e**3)
        speed.append(v)
        if i < n - 1:
            arc += ds[i]
    t = [0.0]
    for i in range(n - 1):
        t.append(t[-1] + max(ds[i], 1e-12 * length) / (0.5 * (speed[i] + speed[i + 1])))
    return np.array(t) * (total_time / t[-1])


def _wobbly_stroke(seed: int, n: int = 25, scale: float = 1.0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    steps = rng.normal(size=(n - 1, 2)) * rng.uniform(0.2, 2.0, size=(n - 1, 1))
    return scale * np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)])


@pytest.mark.parametrize(
    "kwargs",
    [
        {},
        {"smooth": 0.0, "ramp": 0.0},
        {"smooth": 0.5, "curvature_range": (0.5, 200.0)},
        {"smooth": 1.5, "ramp": 0.3, "ramp_floor": 0.5, "total_time": 2.5},
        {"smooth": 3.0, "curvature_range": (10.0, 20.0), "ramp": 0.6, "ramp_floor": 0.05},
    ],
)
def test_timestamps_follow_the_law_vertex_by_vertex(kwargs):
    for seed, scale in [(1, 1.0), (2, 0.01), (3, 40.0)]:
        pts = _wobbly_stroke(seed, scale=scale)
        got = sl.power_law_timestamps(pts, **kwargs)
        np.testing.assert_allclose(got, _timestamps_by_hand(pts, **kwargs), rtol=1e-10, atol=1e-13)


def test_timestamps_of_a_hand_computed_corner():
    # (0,0) -> (1,0) -> (1,1) -> (1,3): segments 1, 1, 2 (length 4); a right angle at the
    # second point over a mean segment of 1 gives kappa L = (pi/2) / 1 * 4 = 2 pi, no turn at
    # the third; the ends copy their neighbours and the range (1, 100) clips the 0 to 1.
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [1.0, 3.0]])
    a = (2 * math.pi) ** (-1.0 / 3.0)  # vertex speeds a, a, 1, 1
    dt = np.array([1 / a, 1 / (0.5 * (a + 1)), 2.0])
    expect = np.concatenate([[0.0], np.cumsum(dt)]) / dt.sum() * 3.0
    got = sl.power_law_timestamps(pts, 3.0, smooth=0.0, curvature_range=(1.0, 100.0), ramp=0.0)
    np.testing.assert_allclose(got, expect, rtol=1e-13)


def test_timestamps_of_a_circular_arc_and_a_line_are_uniform_without_a_ramp():
    u = np.linspace(0.0, math.pi, 31)
    arc = np.column_stack([np.cos(u), np.sin(u)])  # kappa L = pi at every vertex
    t = sl.power_law_timestamps(arc, curvature_range=(1.0, 10.0), ramp=0.0)
    np.testing.assert_allclose(t, np.linspace(0.0, 1.0, 31), rtol=1e-12, atol=1e-15)
    line = np.column_stack([np.linspace(0.0, 3.0, 9), np.linspace(0.0, -1.0, 9)])
    t = sl.power_law_timestamps(line, total_time=4.0, ramp=0.0)
    np.testing.assert_allclose(t, np.linspace(0.0, 4.0, 9), rtol=1e-12, atol=1e-15)


def test_timestamps_give_a_repeated_point_a_tiny_but_positive_duration():
    # a resting pen: the zero segment lasts 1e-12 of the length over the speed there
    pts = _wobbly_stroke(4, n=12, scale=30.0)
    pts = np.vstack([pts[:6], pts[5:6], pts[6:]])
    got = sl.power_law_timestamps(pts)
    expect = _timestamps_by_hand(pts)
    assert np.all(np.diff(got) > 0)
    np.testing.assert_allclose(np.diff(got), np.diff(expect), rtol=1e-4)
    np.testing.assert_allclose(got, expect, rtol=1e-10)


def test_timestamps_of_degenerate_strokes():
    np.testing.assert_array_equal(sl.power_law_timestamps(np.zeros((0, 2))), np.zeros(0))
    np.testing.assert_array_equal(sl.power_law_timestamps([[0.3, 0.4]], total_time=2.0), [0.0])
    two = sl.power_law_timestamps([[0.0, 0.0], [0.5, 0.0]], total_time=2.0)
    np.testing.assert_allclose(two, [0.0, 2.0], rtol=1e-15)
    # no extent, or an extent that is not finite: evenly spaced times
    still = np.tile([[0.2, -0.1]], (4, 1))
    np.testing.assert_allclose(sl.power_law_timestamps(still, total_time=3.0), [0, 1, 2, 3])
    wild = np.array([[0.0, 0.0], [np.inf, 0.0], [1.0, 0.0]])
    np.testing.assert_allclose(sl.power_law_timestamps(wild, total_time=2.0), [0.0, 1.0, 2.0])
    # integer coordinates are fine
    ints = np.array([[0, 0], [1, 0], [1, 1], [1, 3]])
    np.testing.assert_allclose(
        sl.power_law_timestamps(ints), _timestamps_by_hand(ints.astype(float)), rtol=1e-12
    )


# ----------------------------------------------------------------------------------------------
# extraction
# ----------------------------------------------------------------------------------------------

T10 = 0.1 * np.arange(8)  # times of the hand-made speed arrays below


@pytest.mark.parametrize(
    ("sp", "peak", "step", "expect"),
    [
        # walk right over 0.8 and 0.6 to the crossing between 0.6 and 0.2: a quarter of the way
        ([0.2, 0.6, 1.0, 0.8, 0.6, 0.2, 0.1, 0.0], 2, +1, (0.425, True)),
        # walk left to the crossing between index 1 and the first sample
        ([0.2, 0.6, 1.0, 0.8, 0.6, 0.2, 0.1, 0.0], 2, -1, (0.075, True)),
        # the first neighbour is already below the level
        ([0.0, 0.1, 0.3, 1.0, 0.9, 0.8, 0.7, 0.6], 3, -1, (0.3 - 0.1 * 0.5 / 0.7, True)),
        # a sample exactly at the level ends the walk there
        ([0.0, 0.1, 0.5, 1.0, 0.9, 0.8, 0.7, 0.6], 3, -1, (0.2, True)),
        # still above the level at the edge of the array: stop there, no crossing
        ([0.7, 0.9, 1.0, 0.8, 0.4, 0.2, 0.1, 0.0], 2, -1, (0.0, False)),
        ([0.0, 0.1, 0.2, 0.4, 1.0, 0.9, 0.8, 0.7], 4, +1, (0.7, False)),
        # a valley (the speed rises again) before the level: stop at its bottom
        ([0.1, 0.6, 1.0, 0.7, 0.8, 0.2, 0.1, 0.0], 2, +1, (0.3, False)),
        ([0.0, 0.9, 0.7, 1.0, 0.4, 0.2, 0.1, 0.0], 3, -1, (0.2, False)),
        # a plateau is no valley: walk on
        ([0.0, 0.1, 1.0, 0.7, 0.7, 0.3, 0.1, 0.0], 2, +1, (0.4 + 0.1 * 0.2 / 0.4, True)),
    ],
)
def test_crossing_on_hand_made_speeds(sp, peak, step, expect):
    sp = np.array(sp)
    turn = np.zeros_like(sp)
    t, ok = sl._crossing(T10, sp, turn, peak, 0.5, step)
    assert ok == expect[1]
    assert t == pytest.approx(expect[0], abs=1e-12)


def test_crossing_stops_where_the_direction_has_turned_beyond_90_degrees():
    sp = np.array([0.0, 0.2, 0.6, 1.0, 0.9, 0.8, 0.7, 0.1])
    quarter = math.pi / 2
    # turned by more than 90 degrees at index 5: stop before it
    turn = np.array([0, 0, 0, 0, 0.2, quarter + 1e-9, 0, 0])
    assert sl._crossing(T10, sp, turn, 3, 0.5, +1) == (pytest.approx(0.4), False)
    # exactly 90 degrees is still one component
    turn = np.array([0, 0, 0, 0, 0.2, quarter, quarter, quarter])
    t, ok = sl._crossing(T10, sp, turn, 3, 0.5, +1)
    assert ok and t == pytest.approx(0.6 + 0.1 * 0.2 / 0.6)
    # the sample beyond the crossing has turned too far: the crossing is not trusted
    turn = np.array([0, 0, 0, 0, 0, 0, 0, quarter + 0.1])
    assert sl._crossing(T10, sp, turn, 3, 0.5, +1) == (pytest.approx(0.6), False)
    # the same on the way left
    turn = np.array([0, quarter + 0.5, 0, 0, 0, 0, 0, 0])
    assert sl._crossing(T10, sp, turn, 3, 0.5, -1) == (pytest.approx(0.2), False)
    turn = np.array([0, 0, quarter + 0.5, 0, 0, 0, 0, 0])
    assert sl._crossing(T10, sp, turn, 3, 0.5, -1) == (pytest.approx(0.3), False)


T_FINE = np.linspace(0.0, 1.0, 1001)


def _tent(t, tp, a, b, height):
    """Piecewise linear peak at ``tp`` that halves at ``tp - a`` and ``tp + b``."""
    left = height * (1.0 - (tp - t) / (2.0 * a))
    right = height * (1.0 - (t - tp) / (2.0 * b))
    return np.clip(np.where(t <= tp, left, right), 0.0, None)


def _along(speed, t, angles):
    """Velocity of the given speed whose direction is ``angles[k]`` on ``[edges[k], ...)``."""
    direction = np.full(t.shape, angles[0][1])
    for edge, angle in angles[1:]:
        direction = np.where(t >= edge, angle, direction)
    return np.column_stack([speed * np.cos(direction), speed * np.sin(direction)])


def _expected_component(peak, sigma, mode, tp, times, angles):
    """What the closed form makes of a peak: sigma, the mode's offset, the angles at the three
    times (half-maximum points and peak)."""
    t0 = tp - mode
    mu = math.log(mode) + sigma**2
    d = peak * sigma * math.sqrt(2 * math.pi) * mode * math.exp(0.5 * sigma**2)
    cdf = norm.cdf((np.log(np.asarray(times) - t0) - mu) / sigma)
    rel = np.angle(np.exp(1j * (np.asarray(angles) - angles[1])))
    delta = (rel[2] - rel[0]) / (cdf[2] - cdf[0]) if cdf[2] - cdf[0] > 0.2 else 0.0
    delta = float(np.clip(delta, -math.pi, math.pi))
    ths = angles[1] - delta * cdf[1]
    return np.array([d, t0, mu, sigma, ths, ths + delta])


@pytest.mark.parametrize(
    ("ap", "left", "right", "delta_sign"),
    [(1.52, -0.5, 0.7, 0), (0.4, -1.25, 1.25, 1), (0.4, 1.25, -1.25, -1)],
)
def test_init_component_reads_a_skewed_peak_in_closed_form(ap, left, right, delta_sign):
    # half maximum a = 0.05 before and b = 0.1 after the peak: sigma = ln(b / a) / H, the
    # mode is a b / (b - a) after t0; directions change between the three points (relative
    # to the peak's: ap + left + right, about pi, is no special case)
    tp, a, b, height = 0.3, 0.05, 0.1, 0.8
    angles = [(0, ap + left), (0.275, ap), (0.35, ap + right)]
    v = _along(_tent(T_FINE, tp, a, b, height), T_FINE, angles)
    got = sl._init_component(T_FINE, v)
    sigma = math.log(b / a) / H
    expect = _expected_component(
        height, sigma, a * b / (b - a), tp, [tp - a, tp, tp + b], [ap + left, ap, ap + right]
    )
    np.testing.assert_allclose(got, expect, rtol=1e-9, atol=1e-12)
    sweep = got[sl.THETA_E] - got[sl.THETA_S]
    if delta_sign:  # a sweep of more than pi is clipped
        assert sweep == pytest.approx(delta_sign * math.pi, rel=1e-12)
    else:
        assert 1.0 < sweep < 2.0


@pytest.mark.parametrize(("a", "b"), [(0.05, 0.05), (0.02, 0.1), (0.05, 0.055)])
def test_init_component_assumes_sigma_0_3_for_an_unusable_skew(a, b):
    # symmetric, too skewed (sigma > 1) or nearly symmetric (sigma < 0.15): sigma = 0.3 and
    # the mode from the distance of the two half-maximum points
    tp, height, ang = 0.5, 2.5, -2.0
    v = _along(_tent(T_FINE, tp, a, b, height), T_FINE, [(0, ang)])
    got = sl._init_component(T_FINE, v)
    up, down = math.exp(0.3 * H), math.exp(-0.3 * H)
    mode = (a + b) / (up - down)
    expect = _expected_component(height, 0.3, mode, tp, [tp - a, tp, tp + b], [ang] * 3)
    np.testing.assert_allclose(got, expect, rtol=1e-9, atol=1e-12)


def test_init_component_of_a_peak_cut_off_at_the_start():
    # the peak is the first sample: only the falling half-maximum point (b = 0.1 later)
    b, height, ap, a2 = 0.1, 0.6, 1.0, 1.9
    t = T_FINE + 0.2
    v = _along(_tent(t, 0.2, 0.05, b, height), t, [(0, ap), (0.25, a2)])
    got = sl._init_component(t, v)
    mode = b / (math.exp(0.3 * H) - 1.0)
    expect = _expected_component(height, 0.3, mode, 0.2, [0.2, 0.2, 0.2 + b], [ap, ap, a2])
    np.testing.assert_allclose(got, expect, rtol=1e-9, atol=1e-12)
    assert got[sl.THETA_E] - got[sl.THETA_S] > 1.0


def test_init_component_of_a_peak_cut_off_at_the_end():
    a, height, ap, a1 = 0.1, 1.7, -0.3, -1.0
    v = _along(_tent(T_FINE, 1.0, a, 0.05, height), T_FINE, [(0, a1), (0.95, ap)])
    got = sl._init_component(T_FINE, v)
    mode = a / (1.0 - math.exp(-0.3 * H))
    expect = _expected_component(height, 0.3, mode, 1.0, [1.0 - a, 1.0, 1.0], [a1, ap, ap])
    np.testing.assert_allclose(got, expect, rtol=1e-9, atol=1e-12)
    assert got[sl.THETA_E] - got[sl.THETA_S] > 1.0


def test_init_component_without_half_maximum_points_takes_a_twentieth_of_the_span():
    # constant speed on [1, 3]: no crossing on either side; the mode is 0.05 * 2
    t = np.linspace(1.0, 3.0, 201)
    v = _along(np.full(t.shape, 0.9), t, [(0, 0.5)])
    got = sl._init_component(t, v)
    expect = _expected_component(0.9, 0.3, 0.1, 1.0, [1.0, 1.0, 3.0], [0.5] * 3)
    np.testing.assert_allclose(got, expect, rtol=1e-9, atol=1e-12)


def test_init_component_between_two_valleys_keeps_the_peak_direction():
    # both walks stop one sample from the peak: the three times are too close for a sweep
    sp = np.full(T_FINE.shape, 0.95)
    p = 400
    sp[p], sp[p - 1], sp[p + 1] = 1.0, 0.9, 0.9
    v = _along(sp, T_FINE, [(0, 0.3), (0.4 - 5e-4, 0.8), (0.4 + 5e-4, 1.3)])
    got = sl._init_component(T_FINE, v)
    expect = _expected_component(1.0, 0.3, 0.05, 0.4, [0.399, 0.4, 0.401], [0.3, 0.8, 1.3])
    np.testing.assert_allclose(got, expect, rtol=1e-9, atol=1e-12)
    assert got[sl.THETA_S] == pytest.approx(0.8) and got[sl.THETA_E] == pytest.approx(0.8)


def test_init_component_of_a_spike_keeps_the_mode_above_a_thousandth_of_the_span():
    t = np.linspace(0.0, 2.0, 4001)
    sp = np.zeros(t.shape)
    sp[0] = 3.0
    v = _along(sp, t, [(0, 0.3)])
    got = sl._init_component(t, v)
    t2 = 0.5 * t[1]  # the falling half maximum, halfway to the second sample
    assert t2 / (math.exp(0.3 * H) - 1.0) < 2e-3  # the mode this would give is too small
    expect = _expected_component(3.0, 0.3, 2e-3, 0.0, [0.0, 0.0, t2], [0.3] * 3)
    np.testing.assert_allclose(got, expect, rtol=1e-9, atol=1e-12)


def test_init_component_does_not_read_a_peak_ending_in_a_valley_in_closed_form():
    # the speed falls to 0.75 of the peak 0.1 after it, then rises: the right half maximum is
    # not seen, only the left one (a = 0.05 before the peak) and sigma = 0.3
    tp, a, height = 0.3, 0.05, 1.2
    sp = _tent(T_FINE, tp, a, 0.2, height)
    sp = np.where(T_FINE - tp > 0.1, 0.75 * height + 0.3 * (T_FINE - tp - 0.1), sp)
    got = sl._init_component(T_FINE, _along(sp, T_FINE, [(0, 0.1)]))
    mode = a / (1.0 - math.exp(-0.3 * H))
    expect = _expected_component(height, 0.3, mode, tp, [tp - a, tp, tp + 0.1], [0.1] * 3)
    np.testing.assert_allclose(got, expect, rtol=1e-9, atol=1e-12)


def test_init_component_does_not_read_a_peak_narrower_than_a_thousandth_in_closed_form():
    # half maximum 0.8e-3 before and 1.6e-3 after the peak (a skew that would give sigma =
    # ln 2 / H), but the rise is shorter than 1e-3 of the span: sigma = 0.3
    t = np.linspace(0.0, 1.0, 100001)
    tp, a, b, height = 0.5, 0.8e-3, 1.6e-3, 1.0
    got = sl._init_component(t, _along(_tent(t, tp, a, b, height), t, [(0, -0.7)]))
    mode = (a + b) / (math.exp(0.3 * H) - math.exp(-0.3 * H))
    expect = _expected_component(height, 0.3, mode, tp, [tp - a, tp, tp + b], [-0.7] * 3)
    np.testing.assert_allclose(got, expect, rtol=1e-8, atol=1e-12)


def test_init_component_recovers_a_finely_sampled_lognormal():
    comp = np.array([[1.3, 0.1, -1.5, 0.35, 0.4, 1.4]])
    t = np.linspace(0.0, 1.5, 6001)
    got = sl._init_component(t, _expected_velocity(comp, t))
    # the peak and its half-maximum points are within a sample (2.5e-4) of the exact ones
    np.testing.assert_allclose(got[:4], comp[0, :4], rtol=1e-2, atol=2e-3)
    np.testing.assert_allclose(got[4:], comp[0, 4:], atol=1e-2)


def test_init_component_finds_nothing_in_a_zero_or_undefined_residual():
    assert sl._init_component(T_FINE, np.zeros((T_FINE.shape[0], 2))) is None
    v = np.ones((T_FINE.shape[0], 2))
    v[10] = np.nan
    assert sl._init_component(T_FINE, v) is None


# ----------------------------------------------------------------------------------------------
# fitting: parametrisation, bounds, refinements
# ----------------------------------------------------------------------------------------------


def test_internal_parameters_are_log_width_and_sweep():
    p = np.array([[1.5, 0.1, -1.2, 0.4, 0.3, 1.1], [0.7, -0.2, 0.5, 1.2, -2.0, -3.5]])
    x = sl._to_internal(p)
    expect = [1.5, 0.1, -1.2 + math.log(0.4), 0.4, 0.3, 0.8]
    expect += [0.7, -0.2, 0.5 + math.log(1.2), 1.2, -2.0, -1.5]
    np.testing.assert_allclose(x, expect, rtol=1e-15, atol=1e-15)
    assert x.shape == (12,)
    np.testing.assert_array_equal(p[0], [1.5, 0.1, -1.2, 0.4, 0.3, 1.1])  # input untouched
    np.testing.assert_allclose(sl._to_params(x), p, rtol=1e-14, atol=1e-15)
    # a single component given as a flat vector
    np.testing.assert_allclose(sl._to_internal(p[0]), expect[:6], rtol=1e-15)


@pytest.mark.parametrize(
    ("theta_s", "wrapped"),
    [(0.3, 0.3), (3.5, 3.5 - 2 * math.pi), (-4.0, -4.0 + 2 * math.pi), (7.0, 7.0 - 2 * math.pi)],
)
def test_to_params_wraps_theta_s_and_keeps_the_sweep(theta_s, wrapped):
    x = np.array([1.0, 0.2, -1.0, 0.5, theta_s, 0.9, 2.0, 0.0, 0.0, 0.3, 0.0, -0.4])
    before = x.copy()
    p = sl._to_params(x)
    assert p.shape == (2, 6)
    np.testing.assert_array_equal(x, before)
    np.testing.assert_allclose(
        p[0], [1.0, 0.2, -1.0 - math.log(0.5), 0.5, wrapped, wrapped + 0.9], rtol=1e-14
    )
    np.testing.assert_allclose(p[1], [2.0, 0.0, -math.log(0.3), 0.3, 0.0, -0.4], rtol=1e-14)
    assert -math.pi <= p[0, sl.THETA_S] < math.pi


def test_to_params_maps_pi_to_minus_pi():
    p = sl._to_params(np.array([1.0, 0.0, 0.0, 1.0, math.pi, 0.5]))
    assert p[0, sl.THETA_S] == pytest.approx(-math.pi, abs=1e-15)
    assert p[0, sl.THETA_E] == pytest.approx(-math.pi + 0.5, abs=1e-15)


def test_chain_width_turns_mu_sigma_derivatives_into_width_sigma_ones():
    params = TWO.copy()
    t = np.linspace(0.0, 1.2, 61)
    _, jac = sl._displacements(params, t, with_jacobian=True)
    jac_mu = jac[sl.MU].copy()
    out = sl._chain_width(jac, params)
    assert out is jac  # in place
    np.testing.assert_array_equal(out[sl.MU], jac_mu)  # d/dw at fixed sigma is d/dmu

    def disp_at(w, sigma, i):  # mu = w - ln(sigma)
        p = params.copy()
        p[i, sl.SIGMA] = sigma
        p[i, sl.MU] = w - math.log(sigma)
        return sl._displacements(p, t, with_jacobian=False)[0][i]

    h = 1e-6
    for i in range(2):
        w = params[i, sl.MU] + math.log(params[i, sl.SIGMA])
        s = params[i, sl.SIGMA]
        fd = (disp_at(w, s + h, i) - disp_at(w, s - h, i)) / (2 * h)
        np.testing.assert_allclose(out[sl.SIGMA, i], fd, rtol=1e-6, atol=1e-6 * np.abs(fd).max())


def test_bounds_written_out_by_hand():
    t = np.array([0.5, 0.7, 1.0, 1.5, 2.5])  # span 2, mean spacing 0.5
    lo, hi = sl._bounds(2, t, length=3.0)
    lo1 = [0.0, 0.5 - 2.0, math.log(0.5), 0.05, -np.inf, -math.pi]
    hi1 = [6.0, 2.5, 3.0, 1.5, np.inf, math.pi]
    np.testing.assert_allclose(lo, lo1 * 2, rtol=1e-15)
    np.testing.assert_allclose(hi, hi1 * 2, rtol=1e-15)
    lo, hi = sl._bounds(1, t, length=0.25)
    assert lo.shape == hi.shape == (6,)
    assert hi[0] == 0.5


def test_reconstruct_puts_the_start_at_the_mean_residual():
    t = np.linspace(0.0, 1.0, 50)
    rng = np.random.default_rng(9)
    points = sl.trajectory(TWO, t) + np.array([0.4, -0.3]) + rng.normal(0, 0.01, (50, 2))
    recon, start, snr = sl._reconstruct(TWO, points, t)
    rel = _trajectory_by_integration(TWO, t)
    np.testing.assert_allclose(start, (points - rel).mean(axis=0), atol=1e-5)
    np.testing.assert_allclose(recon, rel + start, atol=1e-5)
    signal = np.sum((points - points.mean(axis=0)) ** 2)
    noise = np.sum((points - recon) ** 2)
    assert snr == pytest.approx(10 * math.log10(signal / noise), rel=1e-9)
    bad = TWO.copy()
    bad[0, sl.D] = np.nan
    assert sl._reconstruct(bad, points, t)[2] == -np.inf


def _trajectory_by_integration(params, t):
    fine = np.linspace(min(t[0], params[:, sl.T0].min()) - 0.01, t[-1], 40001)
    vel = _expected_velocity(params, fine)
    pos = np.column_stack(
        [integrate.cumulative_trapezoid(vel[:, i], fine, initial=0.0) for i in range(2)]
    )
    return np.column_stack([np.interp(t, fine, pos[:, i]) for i in range(2)])


def _point_snr(params, points, t):
    rel = sl.trajectory(params, t)
    start = (points - rel).mean(axis=0)
    signal = np.sum((points - points.mean(axis=0)) ** 2)
    return 10 * math.log10(signal / np.sum((points - rel - start) ** 2))


TRUTH = THREE[:2]
NUDGE = np.array([[1.06, 0.012, 0.05, 1.1, 0.06, -0.05], [0.95, -0.01, -0.04, 0.92, -0.05, 0.07]])


def _nudged(params):
    p = params.copy()
    k = p.shape[0]
    p[:, [sl.D, sl.SIGMA]] *= NUDGE[:k, [sl.D, sl.SIGMA]]
    for col in (sl.T0, sl.MU, sl.THETA_S, sl.THETA_E):
        p[:, col] += NUDGE[:k, col]
    return p


def test_refine_points_recovers_a_known_stroke_from_a_nudged_start():
    t = np.linspace(0.0, 1.0, 60)
    points = sl.trajectory(TRUTH, t, np.array([0.3, -0.2]))
    length = float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())
    start = _nudged(TRUTH)
    assert _point_snr(start, points, t) < 25.0
    got = sl._refine_points(start, points, t, length, max_nfev=40)
    assert got.shape == (2, 6)
    assert _point_snr(got, points, t) > 80.0
    np.testing.assert_allclose(got, TRUTH, rtol=1e-4, atol=1e-4)
    # the start point is eliminated: an offset of all points changes nothing
    shifted = sl._refine_points(start, points + np.array([5.0, -3.0]), t, length, 40)
    np.testing.assert_allclose(shifted, got, rtol=1e-6, atol=1e-8)
    # one evaluation: the start as it is, clipped into the bounds
    np.testing.assert_allclose(sl._refine_points(start, points, t, length, 1), start, rtol=1e-14)
    outside = start.copy()
    outside[0, sl.D], outside[1, sl.SIGMA] = -0.5, 2.0
    clipped = sl._refine_points(outside, points, t, length, 1)
    assert clipped[0, sl.D] == 0.0 and clipped[1, sl.SIGMA] == 1.5
    width = outside[1, sl.SIGMA] * math.exp(outside[1, sl.MU])  # kept: the bound is on sigma
    assert clipped[1, sl.SIGMA] * math.exp(clipped[1, sl.MU]) == pytest.approx(width, rel=1e-14)


def test_refine_points_keeps_the_sweep_within_pi():
    t = np.linspace(0.0, 1.0, 60)
    turning = np.array([[0.8, 0.05, -1.2, 0.3, 1.0, -3.0]])
    start = turning.copy()
    turning[0, sl.THETA_E] = turning[0, sl.THETA_S] - 4.0
    points = _trajectory_by_integration(turning, t)
    length = float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())
    got = sl._refine_points(start, points, t, length, 30)
    assert got[0, sl.THETA_E] - got[0, sl.THETA_S] == pytest.approx(-math.pi, rel=1e-12)


def test_refine_points_stops_at_the_first_point_reaching_stop_snr():
    # noisy points: the SNR levels off near 46 dB in small steps
    t = np.linspace(0.0, 1.0, 60)
    rng = np.random.default_rng(2)
    points = sl.trajectory(TRUTH, t, np.array([0.3, -0.2])) + rng.normal(0, 2e-3, (60, 2))
    length = float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())
    start = _nudged(TRUTH)
    path = [sl._refine_points(start, points, t, length, m) for m in range(1, 13)]
    snrs = [_point_snr(p, points, t) for p in path]
    assert all(b >= a - 1e-9 for a, b in itertools.pairwise(snrs))  # never worse
    # a stop just below a point of the path whose predecessor is close below it
    m = next(m for m in range(1, 12) if snrs[m - 1] + 0.1 < snrs[m] < snrs[m - 1] / 0.93)
    got = sl._refine_points(start, points, t, length, 12, stop_snr_db=snrs[m] - 0.05)
    np.testing.assert_array_equal(got, path[m])
    # the default goes on to the end
    np.testing.assert_array_equal(sl._refine_points(start, points, t, length, 12), path[-1])
    assert snrs[-1] > snrs[m] + 0.01


def _support_rows(comp, t):
    v = _expected_speeds(comp[None, :], t)[0]
    return v > 0.02 * v.max()


def test_refine_component_fits_the_residual_on_its_own_support_only():
    # the residual holds the component and, far later, another one; the other one does not
    # pull the fit, a start with a peak speed below 1 recovers the component
    t = np.linspace(0.0, 2.0, 200)
    comp = np.array([0.12, 0.02, -1.6, 0.25, 0.4, 1.3])
    other = np.array([2.0, 0.6, -1.2, 0.2, -2.0, -1.0])  # starts in the far tail of comp
    v_res = _expected_velocity(np.vstack([comp, other]), t)
    start = _nudged(comp[None, :])[0]
    assert _expected_speeds(start[None, :], t).max() < 1.0
    assert not np.any(_support_rows(start, t) & _support_rows(other, t))
    length = 3.0
    got = sl._refine_component(start, v_res, t, length, max_nfev=40)
    assert got.shape == (1, 6)
    np.testing.assert_allclose(got[0], comp, rtol=1e-7, atol=1e-9)


def test_refine_component_keeps_the_start_when_the_fit_vanishes():
    t = np.linspace(0.0, 1.0, 80)
    start = np.array([0.5, 0.05, -1.5, 0.3, 0.2, 0.9])
    # nothing to fit: the amplitude goes to zero, the start comes back (clipped to the bounds)
    got = sl._refine_component(start, np.zeros((80, 2)), t, 1.0, max_nfev=30)
    np.testing.assert_allclose(got[0], start, rtol=1e-13)
    # a residual 1.5e-3 as strong as the start: kept, as more than 1e-3 of the start's D
    weak = start.copy()
    weak[sl.D] *= 1.5e-3
    got = sl._refine_component(start, _expected_velocity(weak[None, :], t), t, 1.0, 60)
    assert got[0, sl.D] == pytest.approx(weak[sl.D], rel=1e-3)
    # 0.5e-3 as strong: the start again
    weak[sl.D] = start[sl.D] * 0.5e-3
    got = sl._refine_component(start, _expected_velocity(weak[None, :], t), t, 1.0, 60)
    np.testing.assert_allclose(got[0], start, rtol=1e-13)


def test_refine_component_clips_the_start_into_the_bounds():
    t = np.linspace(0.0, 1.0, 80)
    start = np.array([0.5, 0.05, -1.5, 2.5, 0.2, 0.9])  # sigma above 1.5
    got = sl._refine_component(start, np.zeros((80, 2)), t, 1.0, max_nfev=5)
    clipped = sl._to_params(np.clip(sl._to_internal(start), *sl._bounds(1, t, 1.0)))
    np.testing.assert_allclose(got, clipped, rtol=1e-13)
    assert got[0, sl.SIGMA] == 1.5


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_refine_component_keeps_the_sweep_within_pi(sign):
    # the residual turns by 4 radians: the fit stops at a sweep of pi
    t = np.linspace(0.0, 1.0, 80)
    turning = np.array([0.8, 0.05, -1.2, 0.3, 1.0, 1.0 + sign * 3.0])
    start = turning.copy()
    turning[sl.THETA_E] = turning[sl.THETA_S] + sign * 4.0
    got = sl._refine_component(start, _expected_velocity(turning[None, :], t), t, 1.0, 30)
    assert got[0, sl.THETA_E] - got[0, sl.THETA_S] == pytest.approx(sign * math.pi, rel=1e-12)
    # a start beyond the bound is clipped first (and kept when nothing is left to fit)
    start[sl.THETA_E] = start[sl.THETA_S] + sign * 3.5
    got = sl._refine_component(start, np.zeros((80, 2)), t, 1.0, 30)
    assert got[0, sl.THETA_E] - got[0, sl.THETA_S] == pytest.approx(sign * math.pi, rel=1e-12)
    assert got[0, sl.D] == start[sl.D]


def test_refine_component_from_a_zero_amplitude_uses_every_sample():
    t = np.linspace(0.0, 1.0, 80)
    comp = np.array([0.4, 0.05, -1.5, 0.3, 0.2, 0.9])
    start = comp.copy()
    start[sl.D] = 0.0  # no support: every sample counts
    got = sl._refine_component(start, _expected_velocity(comp[None, :], t), t, 1.0, 30)
    np.testing.assert_allclose(got[0], comp, rtol=1e-6, atol=1e-8)


# ----------------------------------------------------------------------------------------------
# fit
# ----------------------------------------------------------------------------------------------


def _fit_by_the_procedure(
    points, t, target=20.0, max_components=15, margin=3.0, window=6.0, local_nfev=8, polish_nfev=25
):
    """The procedure of the fitting module's docstring, step by step: greedy components from
    the velocity residual, each fitted alone, a joint polish aiming at target + margin when the
    SNR is within ``window`` of the target or after the last component; the best fit seen."""
    length = float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())  # arc length
    v_obs = np.gradient(points, t, axis=0)  # finite differences against the time stamps
    aim = target + margin
    params = np.zeros((0, 6))
    best = (params, points.mean(axis=0), 0.0)
    for k in range(1, max_components + 1):
        v_res = v_obs - sl.velocity(params, t)  # (tested above against scipy)
        comp = sl._init_component(t, v_res)
        if comp is None:
            break
        params = np.vstack([params, sl._refine_component(comp, v_res, t, length, local_nfev)])
        seen = [params]
        snr = _point_snr(params, points, t)
        if snr < aim and (snr >= target - window or k == max_components):
            seen.append(sl._refine_points(params, points, t, length, polish_nfev, aim))
        for candidate in seen:
            candidate_snr = _point_snr(candidate, points, t)
            snr = max(snr, candidate_snr)
            if candidate_snr > best[2]:
                start = (points - sl.trajectory(candidate, t)).mean(axis=0)
                best = (candidate, start, candidate_snr)
        if snr >= target:
            break
    params, start, snr = best
    if snr >= target:
        message = "target SNR reached"
    elif params.shape[0] < max_components:
        message = f"no residual velocity left after {params.shape[0]} components"
    else:
        message = f"SNR {snr:.1f} dB below target after {max_components} components"
    return params, start, snr, message


def _stroke(name: str) -> tuple[np.ndarray, np.ndarray]:
    if name == "known":  # a sigma-lognormal stroke itself
        t = np.linspace(0.0, 1.0, 100)
        return sl.trajectory(THREE, t, np.array([0.2, -0.1])), t
    if name.startswith("walk"):  # jagged pen noise
        rng = np.random.default_rng(int(name[4:]))
        pts = np.cumsum(rng.normal(size=(int(rng.integers(8, 40)), 2)), axis=0)
        return pts, sl.power_law_timestamps(pts)
    u = np.linspace(0.0, 1.0, 80)
    if name == "wave":
        pts = np.column_stack([np.sin(2 * np.pi * u) + 0.3 * u, np.cos(3 * np.pi * u)])
    elif name == "spiral":
        pts = (0.3 + u)[:, None] * np.column_stack([np.cos(4 * np.pi * u), np.sin(4 * np.pi * u)])
    else:  # "zigzag"
        pts = np.column_stack([np.abs(((4 * u) % 2) - 1), 2 * u])
    return pts, sl.power_law_timestamps(pts)


def _assert_same_fit(result, expect):
    params, start, snr, message = expect
    np.testing.assert_allclose(result.params, params, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(result.start, start, rtol=1e-12, atol=1e-12)
    assert result.snr_db == pytest.approx(snr, rel=1e-12)
    assert result.n_components == params.shape[0]
    assert result.message == message


@pytest.mark.parametrize(
    ("name", "kwargs"),
    [
        ("known", {}),
        ("wave", {}),
        ("wave", {"snr_target_db": 23.0, "polish_window_db": 7.0}),
        ("known", {"snr_target_db": 25.0}),
        ("spiral", {"snr_target_db": 30.0, "max_components": 6}),
        ("zigzag", {"snr_target_db": 38.0, "margin_db": 1.5, "local_nfev": 5, "polish_nfev": 10}),
        ("zigzag", {"snr_target_db": 31.0, "polish_window_db": 2.0, "max_components": 9}),
        ("spiral", {"snr_target_db": 21.0, "margin_db": 0.5, "polish_window_db": 0.0}),
        ("spiral", {"snr_target_db": 45.0, "max_components": 4}),  # below target
        ("known", {"max_components": 1}),
        ("zigzag", {"snr_target_db": 50.0, "max_components": 2}),
        # the best fit has fewer components than allowed: 1, and none at all
        ("walk3", {"snr_target_db": 40.0, "max_components": 3, "polish_nfev": 2}),
        ("walk2", {"snr_target_db": 60.0, "max_components": 4}),
    ],
)
def test_fit_follows_its_documented_procedure(name, kwargs):
    points, t = _stroke(name)
    names = {
        "snr_target_db": "target",
        "max_components": "max_components",
        "margin_db": "margin",
        "polish_window_db": "window",
        "local_nfev": "local_nfev",
        "polish_nfev": "polish_nfev",
    }
    expect = _fit_by_the_procedure(points, t, **{names[k]: v for k, v in kwargs.items()})
    result = sl.fit(points, t, **kwargs)
    _assert_same_fit(result, expect)
    target = kwargs.get("snr_target_db", 20.0)
    assert result.success == (expect[2] >= target)
    assert isinstance(result.success, bool)
    assert result.start.dtype == np.float64 and result.start.shape == (2,)
    assert isinstance(result.snr_db, float)
    recon = sl.trajectory(result.params, t, result.start)
    assert result.snr_db == pytest.approx(sl.snr_db(points, recon), rel=1e-12)


def _invalid_inputs():
    t = np.linspace(0.0, 1.0, 6)
    good = np.column_stack([t, t**2])
    nan_point = good.copy()
    nan_point[2, 1] = np.nan
    inf_time = t.copy()
    inf_time[-1] = np.inf
    repeated_time = t.copy()
    repeated_time[3] = repeated_time[2]
    backwards = t[::-1].copy()
    return [
        (good[:, 0], t),  # one-dimensional points
        (np.zeros((6, 2, 1)), t),  # three-dimensional points
        (np.column_stack([good, t]), t),  # three coordinates
        (good, t[:-1]),  # one time too few
        (good, t[:, None]),  # times of the wrong shape
        (good[:2], t[:2]),  # two points
        (nan_point, t),
        (good, inf_time),
        (good, repeated_time),
        (good, backwards),
    ]


@pytest.mark.parametrize("case", range(10))
def test_fit_reports_each_kind_of_invalid_input(case):
    points, t = _invalid_inputs()[case]
    result = sl.fit(points, t)
    assert result.message == "invalid input"
    assert result.params.shape == (0, 6) and result.params.dtype == np.float64
    np.testing.assert_array_equal(result.start, [0.0, 0.0])
    assert result.start.shape == (2,)
    assert result.snr_db == 0.0 and result.n_components == 0 and result.success is False


def test_fit_accepts_three_points_and_small_time_steps():
    t = np.array([0.0, 0.004, 0.01])
    points = np.array([[0.0, 0.0], [0.02, 0.01], [0.05, 0.0]])  # an extent far below 1
    result = sl.fit(points, t)
    assert result.message not in ("invalid input", "zero-extent stroke")
    assert result.n_components >= 1


def test_fit_of_a_stroke_without_extent_stays_at_its_point():
    points = np.tile([0.3, -0.2], (5, 1))
    result = sl.fit(points, np.linspace(0.0, 1.0, 5))
    assert result.message == "zero-extent stroke"
    np.testing.assert_array_equal(result.start, [0.3, -0.2])
    # an extent whose square underflows to zero counts as none: the first point is kept
    tiny = np.zeros((5, 2))
    tiny[1:, 0] = 1e-170
    result = sl.fit(tiny, np.linspace(0.0, 1.0, 5))
    assert result.message == "zero-extent stroke"
    np.testing.assert_array_equal(result.start, [0.0, 0.0])
    assert result.params.shape == (0, 6)
    assert result.snr_db == 0.0 and result.n_components == 0 and result.success is False
    # a stroke symmetric about its mean has an extent
    line = np.column_stack([np.linspace(-1.0, 1.0, 7), np.zeros(7)])
    assert sl.fit(line, np.linspace(0.0, 1.0, 7)).message != "zero-extent stroke"


def test_fit_without_a_usable_velocity_returns_the_mean_point():
    # time steps of 1e-320: the finite-difference velocity overflows, no component starts
    points = np.column_stack([np.linspace(0.0, 1.0, 8), np.linspace(0.0, 1.0, 8) ** 2])
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        result = sl.fit(points, np.arange(8) * 1e-320)
    assert result.message == "no residual velocity left after 0 components"
    np.testing.assert_allclose(result.start, points.mean(axis=0), rtol=1e-15)
    assert result.params.shape == (0, 6)
    assert result.snr_db == 0.0 and result.n_components == 0 and result.success is False


def test_fit_reports_the_snr_it_missed_the_target_by():
    points, t = _stroke("spiral")
    result = sl.fit(points, t, snr_target_db=45.0, max_components=4)
    recon = sl.trajectory(result.params, t, result.start)
    snr = 10 * math.log10(
        np.sum((points - points.mean(axis=0)) ** 2) / np.sum((points - recon) ** 2)
    )
    assert result.message == f"SNR {snr:.1f} dB below target after 4 components"
    assert result.success is False and result.n_components == 4


def _same_result(a, b) -> bool:
    return (
        a.params.shape == b.params.shape
        and np.array_equal(a.params, b.params)
        and a.message == b.message
        and a.snr_db == b.snr_db
    )


@pytest.mark.parametrize(
    ("name", "parameter", "default", "other", "fixed"),
    [
        ("known", "snr_target_db", 20.0, 21.0, {}),
        ("known", "margin_db", 3.0, 4.0, {}),
        ("known", "local_nfev", 8, 9, {}),
        ("wave", "polish_window_db", 6.0, 7.0, {"snr_target_db": 23.0}),
        ("wave", "max_components", 15, 16, {"snr_target_db": 70.0}),
        ("wave", "polish_nfev", 25, 26, {"snr_target_db": 70.0}),
    ],
)
def test_fit_defaults_are_the_documented_values(name, parameter, default, other, fixed):
    points, t = _stroke(name)
    implicit = sl.fit(points, t, **fixed)
    explicit = sl.fit(points, t, **fixed, **{parameter: default})
    assert _same_result(implicit, explicit)
    # on this stroke the parameter matters: one more gives another fit
    assert not _same_result(implicit, sl.fit(points, t, **fixed, **{parameter: other}))
