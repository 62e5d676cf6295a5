"""Fitting a sigma-lognormal model to a stroke: greedy component extraction and joint polish.

:func:`fit` extracts components greedily from the velocity residual (finite differences of the
points against the time stamps minus the model's velocity):

1. *Initialise* a component at the largest residual speed peak from the peak and its
   half-maximum points (a lognormal is a Gaussian in log time, which gives ``t0, mu, sigma`` in
   closed form; a fixed ``sigma = 0.3`` when the peak is near symmetric or cut off; ``D`` from
   the peak height; ``theta_s, theta_e`` from the residual direction at the three points). The
   half-maximum walk stops early at a speed valley or once the direction has turned by 90
   degrees, so a long, turning plateau is split over several components.
2. *Fit* that component alone to the residual velocity around its own support.
3. When the point SNR (below) is within ``polish_window_db`` of the target, and after the last
   component, *polish*: refine all components jointly on the trajectory points, with the start
   point eliminated in closed form (it is the mean residual), until the SNR reaches the target
   plus ``margin_db``.

Both refinements are a small projected Levenberg-Marquardt on analytic Jacobians, with box
bounds ``D in [0, 2 L]``, ``sigma in [0.05, 1.5]``, ``t0 in [t_first - T, t_last]``,
``|theta_e - theta_s| <= pi`` and a component time scale ``sigma exp(mu)`` of at least one mean
sample spacing (narrower components are spikes between samples). Extraction stops once

    SNR = 10 log10( sum_j ||x_j - mean(x)||^2 / sum_j ||x_j - x_hat_j||^2 )

on the trajectory points reaches ``snr_target_db`` or after ``max_components``. The point SNR
is used (not the velocity SNR of the kinematic literature) because the velocity of equidistant
points is synthetic (it comes from the power law), whereas the shape is what augmentation must
preserve. The best fit seen is returned, with ``success=False`` when it misses the target.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from prg.data.sigma_lognormal.extraction import _init_component
from prg.data.sigma_lognormal.model import (
    _component_velocities,
    _displacements,
    component_speeds,
    trajectory,
    velocity,
)
from prg.data.sigma_lognormal.params import (
    MAX_AMPLITUDE,
    MAX_SWEEP,
    MIN_WIDTH,
    MU,
    MU_MAX,
    N_PARAMS,
    SIGMA,
    SIGMA_BOUNDS,
    THETA_E,
    THETA_S,
    D,
    _as_params,
    _empty_params,
)
from prg.data.sigma_lognormal.snr import snr_db
from prg.data.sigma_lognormal.solver import _levenberg_marquardt, _sum_squares


@dataclass
class FitResult:
    """Outcome of :func:`fit`.

    Attributes
    ----------
    params : ndarray, shape (k, 6)
        Fitted components (columns ``D, T0, MU, SIGMA, THETA_S, THETA_E``).
    start : ndarray, shape (2,)
        Pen position before the first component, so ``trajectory(params, t, start)`` is the fit.
    snr_db : float
        Point SNR of the reconstruction (see the module docstring).
    n_components : int
    success : bool
        True when ``snr_db >= snr_target_db``.
    message : str
    """

    params: np.ndarray
    start: np.ndarray
    snr_db: float
    n_components: int
    success: bool
    message: str


def _to_internal(params: np.ndarray) -> np.ndarray:
    """Public ``(k, 6)`` parameters to the optimiser's flat ``D, t0, w, sigma, theta_s, delta``.

    ``w = mu + ln(sigma)`` is the log of the component's time scale (its width in time is about
    ``sigma * exp(mu)``), so a box bound on ``w`` keeps components wider than a sample spacing
    (narrower ones become spikes between samples); ``delta = theta_e - theta_s`` is the sweep.
    """
    x = _as_params(params).copy()
    x[:, MU] += np.log(x[:, SIGMA])
    x[:, THETA_E] -= x[:, THETA_S]
    return x.ravel()


def _to_params(x: np.ndarray) -> np.ndarray:
    """Inverse of :func:`_to_internal`; ``theta_s`` is wrapped to ``[-pi, pi)`` (same model)."""
    p = x.reshape(-1, N_PARAMS).copy()
    p[:, MU] -= np.log(p[:, SIGMA])
    p[:, THETA_S] = np.mod(p[:, THETA_S] + np.pi, 2.0 * np.pi) - np.pi
    p[:, THETA_E] += p[:, THETA_S]
    return p


def _chain_width(jac: np.ndarray, params: np.ndarray) -> np.ndarray:
    """Derivatives (6, k, n) in ``mu, sigma`` to derivatives in ``w, sigma`` (in place)."""
    jac[SIGMA] -= jac[MU] / params[:, SIGMA, None]
    return jac


def _bounds(k: int, t: np.ndarray, length: float) -> tuple[np.ndarray, np.ndarray]:
    """Box bounds of the internal parameters (flattened, see :func:`_to_internal`)."""
    span = float(t[-1] - t[0])
    d_max = MAX_AMPLITUDE * length
    w_min = math.log(MIN_WIDTH * span / (t.shape[0] - 1))
    lo = [0.0, t[0] - span, w_min, SIGMA_BOUNDS[0], -np.inf, -MAX_SWEEP]
    hi = [d_max, t[-1], MU_MAX, SIGMA_BOUNDS[1], np.inf, MAX_SWEEP]
    return np.tile(lo, k), np.tile(hi, k)


def _refine_points(
    params: np.ndarray,
    points: np.ndarray,
    t: np.ndarray,
    length: float,
    max_nfev: int,
    stop_snr_db: float = np.inf,
) -> np.ndarray:
    """Joint refinement of all components on the points; the start point is eliminated.

    Stops early once the point SNR reaches ``stop_snr_db``.
    """
    target = (points - points.mean(axis=0)).T.ravel()
    stop_cost = _sum_squares(target) * 10.0 ** (-stop_snr_db / 10.0)
    k = params.shape[0]

    def evaluate(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        p = _to_params(x)
        disp, jac = _displacements(p, t, with_jacobian=True)
        jac = _chain_width(jac, p)
        total = disp.sum(axis=0)
        centred = total - total.mean()
        res = np.concatenate([centred.real, centred.imag]) - target
        jac = jac - jac.mean(axis=2, keepdims=True)  # (6, k, n) complex
        jr = np.concatenate([jac.real, jac.imag], axis=2).transpose(2, 1, 0)
        return res, jr.reshape(-1, k * N_PARAMS)

    lo, hi = _bounds(k, t, length)
    x = _levenberg_marquardt(evaluate, _to_internal(params), lo, hi, max_nfev, stop_cost)
    return _to_params(x)


def _refine_component(
    comp: np.ndarray, v_res: np.ndarray, t: np.ndarray, length: float, max_nfev: int
) -> np.ndarray:
    """Fit one new component to the residual velocity around its own support."""
    support = component_speeds(comp, t)[0]
    rows = support > 0.02 * support.max() if support.max() > 0 else np.ones(t.shape, bool)
    tw = t[rows]
    target = v_res[rows, 0] + 1j * v_res[rows, 1]

    def evaluate(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        p = _to_params(x)
        vel, jac = _component_velocities(p, tw)
        jac = _chain_width(jac, p)
        diff = vel[0] - target
        res = np.concatenate([diff.real, diff.imag])
        jr = np.concatenate([jac[:, 0].real, jac[:, 0].imag], axis=1)  # (6, 2m)
        return res, jr.T

    lo, hi = _bounds(1, t, length)
    x0 = np.clip(_to_internal(comp), lo, hi)
    fitted = _to_params(_levenberg_marquardt(evaluate, x0, lo, hi, max_nfev))
    # A component fitted away to nothing would be found again at the same peak: keep the start.
    return fitted if fitted[0, D] > 1e-3 * comp[D] else _to_params(x0)


def _reconstruct(params: np.ndarray, points: np.ndarray, t: np.ndarray):
    rel = trajectory(params, t)
    start = (points - rel).mean(axis=0)
    recon = rel + start
    snr = snr_db(points, recon) if np.all(np.isfinite(recon)) else -np.inf
    return recon, start, snr


def fit(
    points: np.ndarray,
    t: np.ndarray,
    snr_target_db: float = 20.0,
    max_components: int = 15,
    margin_db: float = 3.0,
    polish_window_db: float = 6.0,
    local_nfev: int = 8,
    polish_nfev: int = 25,
) -> FitResult:
    """Fit a sigma-lognormal model to a stroke sampled at known times.

    Components are added greedily, each initialised at the largest peak of the residual velocity
    and fitted to that residual around its support. Whenever the point SNR of the greedy model is
    within ``polish_window_db`` of the target (and after the last component), a joint
    refinement of all components on the points ("polish") runs until the SNR reaches
    ``snr_target_db + margin_db`` or ``polish_nfev`` evaluations; extraction stops as soon as the
    target is met.

    Parameters
    ----------
    points : ndarray, shape (n, 2)
    t : ndarray, shape (n,)
        Strictly increasing sample times (see :func:`power_law_timestamps`).
    snr_target_db : float
        Point SNR that counts as success (see the module docstring).
    max_components : int
    margin_db : float
        The polish aims this far above the target, so fits are not all borderline.
    polish_window_db : float
        Polish only when the greedy SNR is at least ``snr_target_db - polish_window_db``.
    local_nfev : int
        Evaluations of the fit of each new component to the residual velocity.
    polish_nfev : int
        Evaluations of each joint refinement on the points.

    Returns
    -------
    FitResult
        Never raises on finite input; ``success`` is False when the target is not reached (or the
        input is degenerate), with the best fit found.
    """
    pts = np.asarray(points, dtype=np.float64)
    tt = np.asarray(t, dtype=np.float64)
    if (
        pts.ndim != 2
        or pts.shape[1] != 2
        or tt.shape != (pts.shape[0],)
        or pts.shape[0] < 3
        or not np.all(np.isfinite(pts))
        or not np.all(np.isfinite(tt))
        or not np.all(np.diff(tt) > 0)
    ):
        return FitResult(_empty_params(), np.zeros(2), 0.0, 0, False, "invalid input")
    if not np.sum((pts - pts.mean(axis=0)) ** 2) > 0:
        return FitResult(_empty_params(), pts[0].copy(), 0.0, 0, False, "zero-extent stroke")

    length = float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())
    v_obs = np.gradient(pts, tt, axis=0)
    aim = snr_target_db + margin_db
    params = _empty_params()
    best = (params, pts.mean(axis=0), 0.0)

    def consider(candidate: np.ndarray) -> float:
        nonlocal best
        _, start, snr = _reconstruct(candidate, pts, tt)
        if snr > best[2]:
            best = (candidate, start, snr)
        return snr

    for n_comp in range(1, max_components + 1):
        v_res = v_obs - velocity(params, tt)
        comp = _init_component(tt, v_res)
        if comp is None:
            break
        params = np.vstack([params, _refine_component(comp, v_res, tt, length, local_nfev)])
        snr = consider(params)
        last = n_comp == max_components
        if snr < aim and (snr >= snr_target_db - polish_window_db or last):
            snr = max(snr, consider(_refine_points(params, pts, tt, length, polish_nfev, aim)))
        if snr >= snr_target_db:
            break
    params, start, snr = best
    success = bool(snr >= snr_target_db)
    if success:
        message = "target SNR reached"
    elif params.shape[0] < max_components:
        message = f"no residual velocity left after {params.shape[0]} components"
    else:
        message = f"SNR {snr:.1f} dB below target after {max_components} components"
    return FitResult(
        params, np.asarray(start, float), float(snr), params.shape[0], success, message
    )
