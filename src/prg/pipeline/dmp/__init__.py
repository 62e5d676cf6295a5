"""Discrete Dynamic Movement Primitives (DMPs) for whole handwritten words, in NumPy.

One DMP encodes a demonstrated trajectory (a 2-D word in centimetres, one DMP per word) as a
stable spring-damper pulled towards the goal plus a learned forcing term that fades out with a
phase. What lives where:

- :mod:`~prg.pipeline.dmp.model`: the formulation (equations, references, why the forcing term
  is not scaled by ``g - y0``, accuracy) and :class:`DMP`, the fitted DMP as plain data, with its
  JSON form (:meth:`DMP.to_dict`, :meth:`DMP.from_dict`).
- :mod:`~prg.pipeline.dmp.settings`: the default constants (``STIFFNESS``, ``DAMPING``,
  ``ALPHA_X``, ...).
- :mod:`~prg.pipeline.dmp.canonical`: the canonical system, :func:`phase`.
- :mod:`~prg.pipeline.dmp.basis`: :func:`basis_count`, :func:`basis_functions`,
  :func:`design_matrix` and its banded form, and the forcing term ``f(x)``.
- :mod:`~prg.pipeline.dmp.targets`: :func:`forcing_targets` from finite differences.
- :mod:`~prg.pipeline.dmp.regression`: :func:`fit_dmp`, the weights by one ridge solve.
- :mod:`~prg.pipeline.dmp.integration`: :func:`rollout`, the exact loop-free integration.
- :mod:`~prg.pipeline.dmp.resample`: :func:`uniform_in_time` for irregularly timed samples.
- :mod:`~prg.pipeline.dmp.validation` and :mod:`~prg.pipeline.dmp.threads`: argument checks and
  single-threaded BLAS.

Everything is imported from here, as before the package was split: ``from prg.pipeline.dmp
import DMP, fit_dmp, rollout``.
"""

from __future__ import annotations

# The underscored helpers (imported ``as`` themselves) stay reachable here, as before the
# split: the tests use some of them. They are not part of the API (``__all__``).
from prg.pipeline.dmp.basis import _BAND as _BAND
from prg.pipeline.dmp.basis import _NEGLIGIBLE as _NEGLIGIBLE
from prg.pipeline.dmp.basis import _dense as _dense
from prg.pipeline.dmp.basis import _design_band as _design_band
from prg.pipeline.dmp.basis import _forcing as _forcing
from prg.pipeline.dmp.basis import _normalised as _normalised
from prg.pipeline.dmp.basis import basis_count, basis_functions, design_matrix
from prg.pipeline.dmp.canonical import phase
from prg.pipeline.dmp.integration import _HOLD_POINTS as _HOLD_POINTS
from prg.pipeline.dmp.integration import _hold as _hold
from prg.pipeline.dmp.integration import _response as _response
from prg.pipeline.dmp.integration import rollout
from prg.pipeline.dmp.model import _FIELDS as _FIELDS
from prg.pipeline.dmp.model import _VELOCITIES as _VELOCITIES
from prg.pipeline.dmp.model import DMP
from prg.pipeline.dmp.regression import _band_entries as _band_entries
from prg.pipeline.dmp.regression import _banded_gram as _banded_gram
from prg.pipeline.dmp.regression import _ridge as _ridge
from prg.pipeline.dmp.regression import fit_dmp
from prg.pipeline.dmp.resample import uniform_in_time
from prg.pipeline.dmp.settings import (
    ALPHA_X,
    BASIS_MAXIMUM,
    BASIS_MINIMUM,
    BASIS_PER_100_POINTS,
    DAMPING,
    REGULARISATION,
    SAMPLES_PER_BASIS,
    STIFFNESS,
    VELOCITIES,
    WIDTH_FACTOR,
)
from prg.pipeline.dmp.settings import _FloatArray as _FloatArray
from prg.pipeline.dmp.targets import _FD_POINTS as _FD_POINTS
from prg.pipeline.dmp.targets import _derivative as _derivative
from prg.pipeline.dmp.targets import _stencils as _stencils
from prg.pipeline.dmp.targets import _targets as _targets
from prg.pipeline.dmp.targets import forcing_targets
from prg.pipeline.dmp.threads import _blas_controller as _blas_controller
from prg.pipeline.dmp.threads import _one_blas_thread as _one_blas_thread
from prg.pipeline.dmp.validation import _count as _count
from prg.pipeline.dmp.validation import _finite as _finite
from prg.pipeline.dmp.validation import _nonnegative as _nonnegative
from prg.pipeline.dmp.validation import _points as _points
from prg.pipeline.dmp.validation import _positive as _positive
from prg.pipeline.dmp.validation import _real as _real
from prg.pipeline.dmp.validation import _vector as _vector
from prg.pipeline.dmp.validation import _velocities as _velocities

__all__ = [
    "ALPHA_X",
    "BASIS_MAXIMUM",
    "BASIS_MINIMUM",
    "BASIS_PER_100_POINTS",
    "DAMPING",
    "DMP",
    "REGULARISATION",
    "SAMPLES_PER_BASIS",
    "STIFFNESS",
    "VELOCITIES",
    "WIDTH_FACTOR",
    "basis_count",
    "basis_functions",
    "design_matrix",
    "fit_dmp",
    "forcing_targets",
    "phase",
    "rollout",
    "uniform_in_time",
]

# Pickles and reprs name the class where it is imported from, as before the split.
DMP.__module__ = __name__
