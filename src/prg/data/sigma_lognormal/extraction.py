"""Initial guess of one lognormal component from the largest peak of the residual velocity.

The first step of :func:`~prg.data.sigma_lognormal.fitting.fit`: a lognormal is a Gaussian in log time, so the
peak and its half-maximum points give ``t0, mu, sigma`` in closed form (a fixed ``sigma = 0.3``
when the peak is near symmetric or cut off), ``D`` follows from the peak height and ``theta_s,
theta_e`` from the residual direction at the three points. The half-maximum walk stops early at
a speed valley or once the direction has turned by 90 degrees, so a long, turning plateau is
split over several components.
"""

from __future__ import annotations

import math

import numpy as np

from prg.data.sigma_lognormal.model import _SQRT_2PI, _lognormal_terms
from prg.data.sigma_lognormal.params import _TINY, MAX_SWEEP, THETA_E, THETA_S

_HALF_MAX = math.sqrt(2.0 * math.log(2.0))  # half-maximum offset in log time, in units of sigma
_MAX_TURN = math.pi / 2  # largest direction change from a peak covered by its initial component


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
