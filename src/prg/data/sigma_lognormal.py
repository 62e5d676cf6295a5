"""Sigma-lognormal kinematic model of handwriting: evaluation, fitting and perturbation.

A stroke is the vector sum of ``k`` lognormal velocity components. Component ``i`` with
parameters ``(D, t0, mu, sigma, theta_s, theta_e)`` has speed

    v_i(t) = D / (sigma sqrt(2 pi) (t - t0)) exp(-(ln(t - t0) - mu)^2 / (2 sigma^2)),  t > t0

(zero for ``t <= t0``) and direction

    phi_i(t) = theta_s + (theta_e - theta_s) Phi(z),   z = (ln(t - t0) - mu) / sigma,

where ``Phi`` is the standard normal CDF (``Phi(z) = (1 + erf(z / sqrt 2)) / 2``). Because
``v_i dt = D dPhi``, the displacement of one component has a closed form: with
``delta = theta_e - theta_s``,

    p_i(t) = D Phi sinc(delta Phi / 2) [cos(theta_s + delta Phi / 2), sin(theta_s + delta Phi / 2)]

(``sinc(u) = sin(u) / u``), so :func:`trajectory` is exact (no numerical integration) and the fit
has an analytic Jacobian. The trajectory is ``start + sum_i p_i(t)``: ``start`` is the pen position
before the first component begins (``t -> -inf``); it equals the first point only when every
``t0`` precedes the first sample time by enough for the components to be at rest there.

Timing of equidistant points
----------------------------
Preprocessed trajectories are equidistant along the arc, so they carry no speed information.
:func:`power_law_timestamps` assigns times with the **two-thirds power law** of human movement
(tangential speed ``v = K kappa^(-1/3)``, i.e. angular speed proportional to ``kappa^(2/3)``).
Curvature ``kappa`` is the turning angle per unit arc length at each vertex, smoothed with a
Gaussian (``smooth`` samples) and expressed relative to the stroke length ``L`` (``kappa * L`` is
scale free: a full circle has ``2 pi``); it is clipped to ``curvature_range`` so straight parts do
not get infinite speed and sharp corners do not stop the pen completely. The speed is also
multiplied by a smooth onset/offset envelope (the pen accelerates from rest and decelerates to
rest over the first and last ``ramp`` fraction of the arc, from ``ramp_floor`` times the cruise
speed), which matches the bell-shaped speed profiles that lognormals describe. Times are scaled so
the stroke lasts ``total_time``.

Fitting
-------
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

Parameter arrays have shape ``(k, 6)`` with columns ``D, T0, MU, SIGMA, THETA_S, THETA_E``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d
from scipy.special import ndtr

D, T0, MU, SIGMA, THETA_S, THETA_E = range(6)
N_PARAMS = 6

SIGMA_BOUNDS = (0.05, 1.5)
MU_MAX = 3.0  # upper bound of mu (time unit: the stroke's duration is 1 by default)
MIN_WIDTH = 1.0  # smallest sigma * exp(mu), in mean sample spacings
MAX_SWEEP = math.pi  # largest |theta_e - theta_s| of one component, radians
MAX_AMPLITUDE = 2.0  # largest D of one component, in units of the stroke's arc length

_SQRT_2PI = math.sqrt(2.0 * math.pi)
_HALF_MAX = math.sqrt(2.0 * math.log(2.0))  # half-maximum offset in log time, in units of sigma
_TINY = 1e-12
_MAX_TURN = math.pi / 2  # largest direction change from a peak covered by its initial component


def _empty_params() -> np.ndarray:
    return np.zeros((0, N_PARAMS))


def _as_params(params: np.ndarray) -> np.ndarray:
    p = np.asarray(params, dtype=np.float64)
    return p.reshape(-1, N_PARAMS)


def _lognormal_terms(params: np.ndarray, t: np.ndarray):
    """Per-component quantities on the time grid, each shape (k, n).

    Returns ``tau`` (clipped positive), ``active`` (t > t0), ``z``, ``cdf`` (Phi(z), 0 when
    inactive) and ``pdf`` (standard normal density of z, 0 when inactive).
    """
    p = _as_params(params)
    tau = t[None, :] - p[:, T0, None]
    active = tau > _TINY
    tau = np.where(active, tau, 1.0)
    sigma = p[:, SIGMA, None]
    z = (np.log(tau) - p[:, MU, None]) / sigma
    z = np.where(active, z, -np.inf)
    cdf = ndtr(z)
    pdf = np.where(active, np.exp(-0.5 * np.minimum(z * z, 1e4)) / _SQRT_2PI, 0.0)
    return tau, active, z, cdf, pdf


def _speeds_and_cdf(params: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The parameters (k, 6), each component's speed ``v_i(t)`` (k, n) and ``Phi(z)`` (k, n)."""
    p = _as_params(params)
    tau, _, _, cdf, pdf = _lognormal_terms(p, np.asarray(t, dtype=np.float64))
    return p, p[:, D, None] * pdf / (p[:, SIGMA, None] * tau), cdf


def speed(params: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Pen speed at times ``t`` (n,), shape (n,): the norm of :func:`velocity` (not the sum of the
    component speeds)."""
    return np.linalg.norm(velocity(params, t), axis=1)


def component_speeds(params: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Lognormal speed profile ``v_i(t)`` of every component of ``params`` (k, 6) at times ``t``
    (n,): shape (k, n), zero for ``t <= t0``."""
    return _speeds_and_cdf(params, t)[1]


def velocity(params: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Pen velocity, the vector sum of the components of ``params`` (k, 6) at times ``t`` (n,):
    shape (n, 2)."""
    p, v, cdf = _speeds_and_cdf(params, t)
    phi = p[:, THETA_S, None] + (p[:, THETA_E, None] - p[:, THETA_S, None]) * cdf
    return np.column_stack([(v * np.cos(phi)).sum(0), (v * np.sin(phi)).sum(0)])


def _displacements(params: np.ndarray, t: np.ndarray, with_jacobian: bool):
    """Complex displacement of each component (k, n) and optionally its derivatives (6, k, n).

    The derivatives are with respect to ``D, t0, mu, sigma, theta_s, delta`` where
    ``delta = theta_e - theta_s`` (the sweep; the optimiser works in this parametrisation).
    """
    p = _as_params(params)
    tau, _, z, cdf, pdf = _lognormal_terms(p, t)
    d_amp = p[:, D, None]
    sigma = p[:, SIGMA, None]
    th_s = p[:, THETA_S, None]
    delta = p[:, THETA_E, None] - th_s
    half = 0.5 * delta * cdf
    # E = int_0^Phi exp(i delta u) du = Phi sinc(delta Phi / 2) exp(i delta Phi / 2)
    e_int = cdf * np.sinc(half / np.pi) * np.exp(1j * half)
    rot_s = np.exp(1j * th_s)
    disp = d_amp * rot_s * e_int
    if not with_jacobian:
        return disp, None
    # F = dE/d delta = int_0^Phi i u exp(i delta u) du; series near delta = 0.
    small = np.abs(delta) < 1e-3
    safe_delta = np.where(small, 1.0, delta)
    f_closed = (cdf * np.exp(2j * half) - e_int) / safe_delta
    f_series = 1j * (cdf**2 / 2 + 1j * delta * cdf**3 / 3 - delta**2 * cdf**4 / 8)
    f_int = np.where(small, f_series, f_closed)
    d_disp_d_delta = d_amp * rot_s * f_int
    d_disp_d_cdf = d_amp * np.exp(1j * (th_s + delta * cdf))
    dz_scale = pdf / sigma  # dPhi/dz / sigma
    jac = np.empty((N_PARAMS, *disp.shape), dtype=np.complex128)
    jac[D] = rot_s * e_int
    jac[T0] = d_disp_d_cdf * (-dz_scale / tau)
    jac[MU] = d_disp_d_cdf * (-dz_scale)
    jac[SIGMA] = d_disp_d_cdf * (-dz_scale * np.where(np.isfinite(z), z, 0.0))
    jac[THETA_S] = 1j * disp  # with the sweep held fixed
    jac[THETA_E] = d_disp_d_delta  # derivative with respect to the sweep theta_e - theta_s
    return disp, jac


def trajectory(params: np.ndarray, t: np.ndarray, start: np.ndarray | None = None) -> np.ndarray:
    """Pen positions: ``start`` plus the exact time integral of :func:`velocity`.

    Parameters
    ----------
    params : ndarray, shape (k, 6)
    t : ndarray, shape (n,)
    start : ndarray, shape (2,), optional
        Pen position before any component starts (``t -> -inf``); default the origin.

    Returns
    -------
    ndarray, shape (n, 2)
    """
    t = np.asarray(t, dtype=np.float64)
    disp, _ = _displacements(params, t, with_jacobian=False)
    total = disp.sum(axis=0)
    out = np.column_stack([total.real, total.imag])
    if start is not None:
        out = out + np.asarray(start, dtype=np.float64)[None, :]
    return out


def snr_db(points: np.ndarray, reconstruction: np.ndarray) -> float:
    """Signal-to-noise ratio of a reconstruction, in dB.

    Parameters
    ----------
    points, reconstruction : ndarray, shape (n, 2)

    Returns
    -------
    float
        ``10 log10(sum ||x - mean(x)||^2 / sum ||x - x_hat||^2)``; capped at 200 dB for a perfect
        reconstruction.
    """
    signal = float(np.sum((points - points.mean(axis=0)) ** 2))
    noise = float(np.sum((points - reconstruction) ** 2))
    if not signal > 0:
        return 0.0
    return float(min(200.0, 10.0 * math.log10(signal / max(noise, signal * 1e-20))))


# --------------------------------------------------------------------------------------------
# Timing
# --------------------------------------------------------------------------------------------


def power_law_timestamps(
    points: np.ndarray,
    total_time: float = 1.0,
    smooth: float = 2.0,
    curvature_range: tuple[float, float] = (2.0, 60.0),
    ramp: float = 0.1,
    ramp_floor: float = 0.3,
) -> np.ndarray:
    """Time stamps for equidistant points from the two-thirds power law.

    Parameters
    ----------
    points : ndarray, shape (n, 2)
        A stroke; any spacing (the law is applied per segment).
    total_time : float
        Duration of the stroke.
    smooth : float
        Gaussian smoothing of the curvature, in samples.
    curvature_range : (float, float)
        Clipping range of the length-relative curvature ``kappa * L``.
    ramp : float
        Fraction of the arc length over which the pen accelerates from / decelerates to
        ``ramp_floor`` times its cruise speed (``0`` disables the envelope).
    ramp_floor : float
        Relative speed at the very first and last point, in ``(0, 1]``.

    Returns
    -------
    ndarray, shape (n,)
        Strictly increasing, ``t[0] = 0``, ``t[-1] = total_time``.
    """
    pts = np.asarray(points, dtype=np.float64)
    n = pts.shape[0]
    if n < 2:
        return np.zeros(n)
    seg = np.diff(pts, axis=0)
    ds = np.linalg.norm(seg, axis=1)
    length = float(ds.sum())
    if not (np.isfinite(length) and length > 0):
        return np.linspace(0.0, total_time, n)
    s = np.concatenate([[0.0], np.cumsum(ds)]) / length
    kappa_l = np.full(n, curvature_range[0])
    if n >= 3:
        heading = np.arctan2(seg[:, 1], seg[:, 0])
        turn = np.abs(np.angle(np.exp(1j * np.diff(heading))))
        local = 0.5 * (ds[:-1] + ds[1:])
        kappa_l[1:-1] = turn / np.maximum(local, _TINY * length) * length
        kappa_l[0], kappa_l[-1] = kappa_l[1], kappa_l[-2]
        if smooth > 0:
            kappa_l = gaussian_filter1d(kappa_l, smooth, mode="nearest")
    kappa_l = np.clip(kappa_l, *curvature_range)
    vertex_speed = kappa_l ** (-1.0 / 3.0)
    if ramp > 0:
        edge = np.clip(np.minimum(s, 1.0 - s) / ramp, 0.0, 1.0)
        smoothstep = edge * edge * (3.0 - 2.0 * edge)
        vertex_speed = vertex_speed * (ramp_floor + (1.0 - ramp_floor) * smoothstep)
    seg_speed = 0.5 * (vertex_speed[:-1] + vertex_speed[1:])
    dt = np.maximum(ds, _TINY * length) / seg_speed
    t = np.concatenate([[0.0], np.cumsum(dt)])
    return t * (total_time / t[-1])


# --------------------------------------------------------------------------------------------
# Fitting
# --------------------------------------------------------------------------------------------


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


def _crossing(
    t: np.ndarray, sp: np.ndarray, turn: np.ndarray, peak_idx: int, level: float, step: int
) -> tuple[float, bool]:
    """Walk from the peak to where the speed drops to ``level``.

    Returns the (interpolated) time and True, or the time where the walk stopped early and
    False: at a local minimum of the speed (another component takes over) or where the direction
    has turned by more than ``_MAX_TURN`` from the peak's (one component sweeps a limited angle).
    """
    i = peak_idx
    n = sp.shape[0]
    while 0 <= i + step < n and sp[i + step] > level:
        if sp[i + step] > sp[i] or turn[i + step] > _MAX_TURN:
            return t[i], False
        i += step
    j = i + step
    if 0 <= j < n and turn[j] <= _MAX_TURN:
        frac = (sp[i] - level) / max(sp[i] - sp[j], _TINY)
        return t[i] + frac * (t[j] - t[i]), True
    return t[i], False


def _init_component(t: np.ndarray, v_res: np.ndarray) -> np.ndarray | None:
    """One lognormal component from the largest peak of the residual velocity."""
    sp = np.linalg.norm(v_res, axis=1)
    p = int(np.argmax(sp))
    peak = float(sp[p])
    if not (np.isfinite(peak) and peak > 0):
        return None
    tp = float(t[p])
    heading = np.arctan2(v_res[:, 1], v_res[:, 0])
    turn = np.abs(np.angle(np.exp(1j * (heading - heading[p]))))
    t1, ok1 = _crossing(t, sp, turn, p, 0.5 * peak, -1)
    t2, ok2 = _crossing(t, sp, turn, p, 0.5 * peak, +1)
    span = float(t[-1] - t[0])
    min_gap = 1e-3 * span
    sig = None
    if ok1 and ok2 and t2 - tp > min_gap and tp - t1 > min_gap:
        denom = t1 + t2 - 2.0 * tp
        if denom > _TINY:
            t0 = (t1 * t2 - tp * tp) / denom
            if t0 < t1:
                cand = math.log((t2 - t0) / (tp - t0)) / _HALF_MAX
                if 0.15 <= cand <= 1.0:  # narrower: an unreliable, near-symmetric peak
                    sig, mode = cand, tp - t0
    if sig is None:  # skewness unusable or a half-maximum hidden by the edge: assume sigma
        sig = 0.3
        up, down = math.exp(_HALF_MAX * sig), math.exp(-_HALF_MAX * sig)
        if ok1 and ok2:
            mode = (t2 - t1) / (up - down)
        elif ok2:
            mode = (t2 - tp) / (up - 1.0)
        elif ok1:
            mode = (tp - t1) / (1.0 - down)
        else:
            mode = 0.05 * span
        mode = max(mode, min_gap)
    t0 = tp - mode
    mu = math.log(mode) + sig * sig
    d_amp = peak * sig * _SQRT_2PI * mode * math.exp(0.5 * sig * sig)
    # Angles: phi = theta_s + delta * Phi(z), observed at t1, tp, t2.
    comp = np.array([d_amp, t0, mu, sig, 0.0, 0.0])
    times = np.array([min(t1, tp), tp, max(t2, tp)])
    cdf = _lognormal_terms(comp, times)[3][0]
    ang = np.arctan2(
        np.interp(times, t, v_res[:, 1]), np.interp(times, t, v_res[:, 0])
    )  # directions at t1, tp, t2
    rel = np.angle(np.exp(1j * (ang - ang[1])))
    dcdf = cdf[2] - cdf[0]
    delta = (rel[2] - rel[0]) / dcdf if dcdf > 0.2 else 0.0
    delta = float(np.clip(delta, -MAX_SWEEP, MAX_SWEEP))
    theta_s = ang[1] - delta * cdf[1]
    comp[THETA_S], comp[THETA_E] = theta_s, theta_s + delta
    return comp


def _component_velocities(params: np.ndarray, t: np.ndarray):
    """Complex velocity of each component (k, n) and its derivatives (6, k, n).

    Derivatives are with respect to ``D, t0, mu, sigma, theta_s, delta`` (sweep held fixed for
    ``theta_s``), like :func:`_displacements`.
    """
    p = _as_params(params)
    tau, _, z, cdf, pdf = _lognormal_terms(p, t)
    sigma = p[:, SIGMA, None]
    delta = p[:, THETA_E, None] - p[:, THETA_S, None]
    unit = pdf / (sigma * tau) * np.exp(1j * (p[:, THETA_S, None] + delta * cdf))
    vel = p[:, D, None] * unit
    zf = np.where(np.isfinite(z), z, 0.0)
    dvdz = vel * (-zf + 1j * delta * pdf)
    jac = np.empty((N_PARAMS, *vel.shape), dtype=np.complex128)
    jac[D] = unit
    jac[T0] = -dvdz / (sigma * tau) + vel / tau
    jac[MU] = -dvdz / sigma
    jac[SIGMA] = -dvdz * zf / sigma - vel / sigma
    jac[THETA_S] = 1j * vel
    jac[THETA_E] = 1j * vel * cdf
    return vel, jac


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


# Linear algebra of the fit without BLAS or LAPACK. Their results depend on the machine: OpenBLAS
# picks its kernels at run time by CPU (Haswell, SkylakeX, ...) and splits work over threads, each
# variant summing in its own order, and the greedy fit turns such a last-bit difference into other
# components now and then (demo set, before this: 6 failed fits of 5,208 with the SkylakeX
# kernels, 5 with OPENBLAS_CORETYPE=Haswell). numpy's einsum (optimize off) never calls BLAS and
# is not dispatched by CPU, so the fit no longer depends on the BLAS, its kernel or its threads.
# (numpy's exp, log, arctan2 and power still have AVX-512 variants: a CPU without AVX-512 gives
# slightly different fits; README, "Reproducibility".)


def _sum_squares(x: np.ndarray) -> float:
    return float(np.einsum("i,i->", x, x))


_SMALL_SOLVE = 24  # up to this size plain Python floats beat a numpy loop over columns


def _solve_spd(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve ``a x = b`` for a symmetric positive definite ``a`` by Cholesky factorisation.

    Raises ``numpy.linalg.LinAlgError`` when a pivot is not positive (``a`` not numerically
    positive definite).
    """
    if a.shape[0] <= _SMALL_SOLVE:
        return _solve_spd_small(a.tolist(), b.tolist())
    work = np.array(a, dtype=np.float64)
    x = np.array(b, dtype=np.float64)
    n = work.shape[0]
    for j in range(n):  # right-looking; the factor overwrites the lower triangle of work
        pivot = work[j, j]
        if not pivot > 0:
            raise np.linalg.LinAlgError("matrix is not positive definite")
        col = work[j:, j] / math.sqrt(pivot)
        work[j:, j] = col
        work[j + 1 :, j + 1 :] -= np.multiply.outer(col[1:], col[1:])
        x[j] /= col[0]  # forward substitution, column by column
        x[j + 1 :] -= col[1:] * x[j]
    for j in range(n - 1, -1, -1):  # back substitution with the transposed factor
        x[j] /= work[j, j]
        x[:j] -= work[j, :j] * x[j]
    return x


def _solve_spd_small(a: list[list[float]], b: list[float]) -> np.ndarray:
    # Explicit loops, not sum(): Python 3.12 changed sum() of floats to a compensated sum.
    n = len(b)
    low = [[0.0] * n for _ in range(n)]
    for j in range(n):
        row_j = low[j]
        pivot = a[j][j]
        for k in range(j):
            pivot -= row_j[k] * row_j[k]
        if not pivot > 0:
            raise np.linalg.LinAlgError("matrix is not positive definite")
        row_j[j] = diag = math.sqrt(pivot)
        for i in range(j + 1, n):
            row_i = low[i]
            v = a[i][j]
            for k in range(j):
                v -= row_i[k] * row_j[k]
            row_i[j] = v / diag
    y = list(b)
    for i in range(n):
        v = y[i]
        for k in range(i):
            v -= low[i][k] * y[k]
        y[i] = v / low[i][i]
    for i in range(n - 1, -1, -1):
        v = y[i]
        for k in range(i + 1, n):
            v -= low[k][i] * y[k]
        y[i] = v / low[i][i]
    return np.array(y)


def _levenberg_marquardt(
    evaluate, x0: np.ndarray, lo: np.ndarray, hi: np.ndarray, max_nfev: int, stop_cost: float = 0.0
) -> np.ndarray:
    """Projected Levenberg-Marquardt: Marquardt's diagonal scaling, box bounds by clipping.

    Used instead of ``scipy.optimize.least_squares`` because the latter's bounded solver takes an
    SVD per iteration that dominates the run time on these small problems (at most 90 unknowns,
    so damped normal equations, solved by Cholesky, are cheap and well enough conditioned).
    ``evaluate(x)`` returns the residual (m,) and Jacobian (m, p). Stops after ``max_nfev``
    evaluations, when the cost (sum of squares) drops to ``stop_cost`` or stalls. Never increases
    the cost; returns ``x0`` (clipped) if the residual is not finite.
    """
    x = np.clip(x0, lo, hi)
    with np.errstate(all="ignore"):
        res, jac = evaluate(x)
        cost = _sum_squares(res)
        if not np.isfinite(cost):
            return x
        lam, nfev = 1e-3, 1
        while nfev < max_nfev and cost > stop_cost:
            grad = np.einsum("ij,i->j", jac, res)
            normal = np.einsum("ij,ik->jk", jac, jac)
            diag = np.diag(normal)
            scale = np.maximum(diag, 1e-6 * diag.max() + 1e-30)  # no huge steps in idle params
            improved = False
            while nfev < max_nfev and lam < 1e8:
                try:
                    step = _solve_spd(normal + lam * np.diag(scale), -grad)
                except np.linalg.LinAlgError:
                    lam *= 10.0
                    continue
                x_new = np.clip(x + step, lo, hi)
                res_new, jac_new = evaluate(x_new)
                nfev += 1
                cost_new = _sum_squares(res_new)
                if np.isfinite(cost_new) and cost_new < cost:
                    improved = cost - cost_new > 1e-6 * cost
                    x, res, jac, cost = x_new, res_new, jac_new, cost_new
                    lam = max(lam / 3.0, 1e-9)
                    break
                lam *= 4.0
            if not improved:
                break
    return x


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


# --------------------------------------------------------------------------------------------
# Perturbation
# --------------------------------------------------------------------------------------------


def perturb(
    params: np.ndarray,
    rng: np.random.Generator,
    amplitude: float = 0.1,
    rotation_deg: float = 5.0,
    sweep: float = 0.05,
) -> np.ndarray:
    """Random variation of a fitted stroke within the reference's constraints.

    Per component: ``D`` is scaled by ``U(1 - amplitude, 1 + amplitude)``; the component is
    rotated as a whole — ``theta_s`` and ``theta_e`` both shifted by one offset
    ``U(-rotation_deg, rotation_deg)`` (degrees) — and each of the two angles gets its own
    sweep-proportional jitter ``U(-sweep, sweep) * (theta_e - theta_s)`` (the original sweep), so
    a component's curvature changes by at most ``2 * sweep`` of itself. (Rotating the two angles
    independently by the full range would change a component's sweep by up to twice the rotation
    range and turns letters into other letters.) Timing (``t0, mu, sigma``) is untouched.

    Parameters
    ----------
    params : ndarray, shape (k, 6)
    rng : numpy.random.Generator
    amplitude, rotation_deg, sweep : float
        Non-negative half-widths of the uniform ranges.

    Returns
    -------
    ndarray, shape (k, 6)
        A new array; the input is not modified.
    """
    p = _as_params(params).copy()
    k = p.shape[0]
    rot = math.radians(rotation_deg)
    sweep_angle = p[:, THETA_E] - p[:, THETA_S]
    scale = rng.uniform(1.0 - amplitude, 1.0 + amplitude, size=k)
    rotation = rng.uniform(-rot, rot, size=k)
    jitter = rng.uniform(-sweep, sweep, size=(k, 2)) * sweep_angle[:, None]
    p[:, D] *= scale
    p[:, THETA_S] += rotation + jitter[:, 0]
    p[:, THETA_E] += rotation + jitter[:, 1]
    return p
