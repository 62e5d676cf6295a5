"""The canonical system: the phase ``x`` that gates the forcing term and fades it out.

``tau x' = -alpha_x x`` with ``x(0) = 1``, so ``x(t) = exp(-alpha_x t / tau)`` in closed form
(no integration); with the default ``alpha_x = ln 100`` the phase is 0.01 at ``t = tau``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from prg.pipeline.dmp.settings import ALPHA_X, _FloatArray


def phase(t: ArrayLike, tau: float, alpha_x: float = ALPHA_X) -> _FloatArray:
    """Closed-form phase of the canonical system, ``x(t) = exp(-alpha_x t / tau)``.

    Parameters
    ----------
    t : array_like, shape (n,)
        Times.
    tau : float
        Time constant (duration), > 0.
    alpha_x : float
        Decay constant, > 0.

    Returns
    -------
    ndarray, shape (n,)
    """
    return np.exp(-alpha_x * np.asarray(t, dtype=np.float64) / tau)
