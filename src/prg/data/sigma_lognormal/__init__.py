"""Sigma-lognormal kinematic model of handwriting: evaluation, fitting and perturbation.

A stroke is the vector sum of ``k`` lognormal velocity components, each with parameters
``(D, t0, mu, sigma, theta_s, theta_e)``. What lives where:

- :mod:`~prg.data.sigma_lognormal.params`: the parameter columns (``D, T0, MU, SIGMA, THETA_S,
  THETA_E``) and the bounds a fit keeps them in.
- :mod:`~prg.data.sigma_lognormal.model`: the lognormal velocity model and its closed-form
  displacement (the formulation): :func:`speed`, :func:`component_speeds`, :func:`velocity`,
  :func:`trajectory`, with the analytic Jacobians of the fit.
- :mod:`~prg.data.sigma_lognormal.timing`: :func:`power_law_timestamps`, times for equidistant
  points from the two-thirds power law.
- :mod:`~prg.data.sigma_lognormal.snr`: :func:`snr_db`, the point SNR of a reconstruction.
- :mod:`~prg.data.sigma_lognormal.extraction`: the initial guess of a component at the largest
  residual velocity peak.
- :mod:`~prg.data.sigma_lognormal.solver`: the BLAS-free Cholesky solve and the projected
  Levenberg-Marquardt of the fit.
- :mod:`~prg.data.sigma_lognormal.fitting`: :func:`fit` and :class:`FitResult` (the fitting
  procedure is described there).
- :mod:`~prg.data.sigma_lognormal.perturbation`: :func:`perturb`, the random variation that
  augmentation draws new strokes with.

Everything is imported from here, as before the package was split: ``from prg.data import
sigma_lognormal as sl; sl.fit(...)``.
"""

from __future__ import annotations

# The underscored helpers (imported ``as`` themselves) stay reachable here, as before the
# split: the tests use some of them. They are not part of the API (``__all__``).
from prg.data.sigma_lognormal.extraction import _HALF_MAX as _HALF_MAX
from prg.data.sigma_lognormal.extraction import _MAX_TURN as _MAX_TURN
from prg.data.sigma_lognormal.extraction import _crossing as _crossing
from prg.data.sigma_lognormal.extraction import _init_component as _init_component
from prg.data.sigma_lognormal.fitting import FitResult, fit
from prg.data.sigma_lognormal.fitting import _bounds as _bounds
from prg.data.sigma_lognormal.fitting import _chain_width as _chain_width
from prg.data.sigma_lognormal.fitting import _reconstruct as _reconstruct
from prg.data.sigma_lognormal.fitting import _refine_component as _refine_component
from prg.data.sigma_lognormal.fitting import _refine_points as _refine_points
from prg.data.sigma_lognormal.fitting import _to_internal as _to_internal
from prg.data.sigma_lognormal.fitting import _to_params as _to_params
from prg.data.sigma_lognormal.model import _SQRT_2PI as _SQRT_2PI
from prg.data.sigma_lognormal.model import _component_velocities as _component_velocities
from prg.data.sigma_lognormal.model import _displacements as _displacements
from prg.data.sigma_lognormal.model import _lognormal_terms as _lognormal_terms
from prg.data.sigma_lognormal.model import _speeds_and_cdf as _speeds_and_cdf
from prg.data.sigma_lognormal.model import component_speeds, speed, trajectory, velocity
from prg.data.sigma_lognormal.params import _TINY as _TINY
from prg.data.sigma_lognormal.params import (
    MAX_AMPLITUDE,
    MAX_SWEEP,
    MIN_WIDTH,
    MU,
    MU_MAX,
    N_PARAMS,
    SIGMA,
    SIGMA_BOUNDS,
    T0,
    THETA_E,
    THETA_S,
    D,
)
from prg.data.sigma_lognormal.params import _as_params as _as_params
from prg.data.sigma_lognormal.params import _empty_params as _empty_params
from prg.data.sigma_lognormal.perturbation import perturb
from prg.data.sigma_lognormal.snr import snr_db
from prg.data.sigma_lognormal.solver import _SMALL_SOLVE as _SMALL_SOLVE
from prg.data.sigma_lognormal.solver import _levenberg_marquardt as _levenberg_marquardt
from prg.data.sigma_lognormal.solver import _solve_spd as _solve_spd
from prg.data.sigma_lognormal.solver import _solve_spd_small as _solve_spd_small
from prg.data.sigma_lognormal.solver import _sum_squares as _sum_squares
from prg.data.sigma_lognormal.timing import power_law_timestamps

__all__ = [
    "MAX_AMPLITUDE",
    "MAX_SWEEP",
    "MIN_WIDTH",
    "MU",
    "MU_MAX",
    "N_PARAMS",
    "SIGMA",
    "SIGMA_BOUNDS",
    "T0",
    "THETA_E",
    "THETA_S",
    "D",
    "FitResult",
    "component_speeds",
    "fit",
    "perturb",
    "power_law_timestamps",
    "snr_db",
    "speed",
    "trajectory",
    "velocity",
]

# Pickles (the fits that augmentation's worker processes send back) and reprs name the class
# where it is imported from, as before the split.
FitResult.__module__ = __name__
