"""Default constants of the DMP (its gains, basis sizes, regularisation) and the array type.

The defaults are those of the formulation in :mod:`prg.pipeline.dmp.model`: ``K = 156.25``,
``D = 2 sqrt(K) = 25`` (critical damping) and ``alpha_x = ln 100`` (the phase falls to 0.01 at
``t = tau``).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

STIFFNESS = 156.25
"""Default spring constant ``K`` (``alpha_z beta_z`` with ``alpha_z = 25``, ``beta_z = 6.25``)."""
DAMPING = 2.0 * math.sqrt(STIFFNESS)
"""Default damping ``D``: critical, ``2 sqrt(K) = 25``."""
ALPHA_X = math.log(100.0)
"""Default canonical-system constant: the phase falls to 0.01 at ``t = tau``."""
WIDTH_FACTOR = 1.0
"""Standard deviation of each Gaussian in units of the spacing between neighbouring centres."""
VELOCITIES = ("rest", "demonstrated")
"""What :func:`fit_dmp` takes for the start and goal velocities (``velocities=``)."""
REGULARISATION = 1e-12
"""Default ridge parameter of :func:`fit_dmp` (on the per-sample mean squared error)."""
BASIS_PER_100_POINTS = 20.0
"""Default basis functions per 100 points of :func:`basis_count`."""
BASIS_MINIMUM = 20
"""Default lower bound of :func:`basis_count`."""
BASIS_MAXIMUM = 2000
"""Default upper bound of :func:`basis_count`."""
SAMPLES_PER_BASIS = 4
"""Least number of integration samples per basis function in :func:`rollout`."""

_FloatArray = NDArray[np.float64]
