"""Augmentation: random variation of a fitted stroke's components within the model's constraints."""

from __future__ import annotations

import math

import numpy as np

from prg.data.sigma_lognormal.params import THETA_E, THETA_S, D, _as_params


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
