"""Parameter layout of a sigma-lognormal model and the bounds a fit keeps the parameters in.

Parameter arrays have shape ``(k, 6)`` with columns ``D, T0, MU, SIGMA, THETA_S, THETA_E``.
"""

from __future__ import annotations

import math

import numpy as np

D, T0, MU, SIGMA, THETA_S, THETA_E = range(6)
N_PARAMS = 6

SIGMA_BOUNDS = (0.05, 1.5)
MU_MAX = 3.0  # upper bound of mu (time unit: the stroke's duration is 1 by default)
MIN_WIDTH = 1.0  # smallest sigma * exp(mu), in mean sample spacings
MAX_SWEEP = math.pi  # largest |theta_e - theta_s| of one component, radians
MAX_AMPLITUDE = 2.0  # largest D of one component, in units of the stroke's arc length

_TINY = 1e-12


def _empty_params() -> np.ndarray:
    return np.zeros((0, N_PARAMS))


def _as_params(params: np.ndarray) -> np.ndarray:
    p = np.asarray(params, dtype=np.float64)
    return p.reshape(-1, N_PARAMS)
