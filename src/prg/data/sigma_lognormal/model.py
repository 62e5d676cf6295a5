"""The lognormal velocity model: component speeds, pen velocity and the exact trajectory.

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
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import ndtr

from prg.data.sigma_lognormal.params import (
    _TINY,
    MU,
    N_PARAMS,
    SIGMA,
    T0,
    THETA_E,
    THETA_S,
    D,
    _as_params,
)

_SQRT_2PI = math.sqrt(2.0 * math.pi)


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
