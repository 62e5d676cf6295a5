"""Fitting a DMP: the forcing-term weights by one ridge-regression solve.

**Fitting** (:func:`fit_dmp`): the demonstration is taken on a uniform time grid over ``[0, tau]``
(``n`` points); velocities and accelerations come from five-point (fourth-order) finite differences
(one-sided near the ends). The target forcing values ``F = (tau^2 y'' + D tau y') / K - (g_m(t) -
y) + (g - y0) x - D tau g' / K`` (``y0`` the first point, ``g`` the last, ``g'`` zero or the last
point's velocity) are regressed on the design matrix
``Phi[k, i] = x_k psi_i(x_k) / sum_j psi_j(x_k)`` with **one** ridge solve for all basis functions
and all dimensions::

    W = argmin (1/n) ||Phi W - F||^2 + regularisation ||W||^2
      = solve(Phi^T Phi / n + regularisation I, Phi^T F / n)     (banded Cholesky; lstsq if 0)
"""

from __future__ import annotations

import functools
import math

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike

from prg.pipeline.dmp.basis import _dense, _design_band, basis_count, basis_functions
from prg.pipeline.dmp.model import DMP
from prg.pipeline.dmp.settings import (
    ALPHA_X,
    REGULARISATION,
    STIFFNESS,
    WIDTH_FACTOR,
    _FloatArray,
)
from prg.pipeline.dmp.targets import _targets
from prg.pipeline.dmp.threads import _one_blas_thread
from prg.pipeline.dmp.validation import (
    _count,
    _nonnegative,
    _points,
    _positive,
    _velocities,
)


def fit_dmp(
    points: ArrayLike,
    tau: float = 1.0,
    n_basis: int | None = None,
    regularisation: float = REGULARISATION,
    *,
    stiffness: float = STIFFNESS,
    damping: float | None = None,
    alpha_x: float = ALPHA_X,
    width_factor: float = WIDTH_FACTOR,
    velocities: str = "rest",
) -> DMP:
    """Fit a DMP to one demonstration with a single ridge-regression solve.

    Parameters
    ----------
    points : array_like, shape (n, dims)
        The demonstration (e.g. a word in centimetres, ``dims = 2``) sampled uniformly in time,
        ``n >= 3`` finite points.
    tau : float
        Its duration, > 0.
    n_basis : int, optional
        Number of basis functions, >= 1; default ``basis_count(n)``.
    regularisation : float
        Ridge parameter ``lambda >= 0`` on the per-sample mean squared error (module docstring);
        0 gives the minimum-norm least-squares solution.
    stiffness : float
        ``K > 0``.
    damping : float, optional
        ``D >= 0``; default ``2 sqrt(K)`` (critical damping).
    alpha_x : float
        Canonical-system constant, > 0.
    width_factor : float
        Basis width in units of the centre spacing, > 0 (:func:`basis_functions`).
    velocities : {"rest", "demonstrated"}
        ``"rest"``: the DMP starts and ends at rest, whatever the demonstration does (a word's
        pen; the default). ``"demonstrated"``: it starts with the demonstration's first
        velocity and ends with its last (finite differences, as for the forcing targets), for
        demonstrations that are already moving at either end (:mod:`prg.pipeline.dmp.model`).

    Returns
    -------
    DMP
        With ``y0 = points[0]``, ``goal = points[-1]``, ``n_samples = n`` and the two velocities.

    Raises
    ------
    ValueError
        (:class:`prg.errors.UsageError`) naming the argument that is out of range.

    Examples
    --------
    A rest-to-rest stroke, fitted over two seconds and rolled out again:

    >>> import numpy as np
    >>> from prg.pipeline.dmp import fit_dmp, rollout
    >>> t = np.linspace(0, 1, 201)
    >>> s = 10 * t**3 - 15 * t**4 + 6 * t**5  # minimum jerk: starts and ends at rest
    >>> stroke = np.column_stack([s, np.sin(np.pi * s)])
    >>> dmp = fit_dmp(stroke, tau=2.0, n_basis=40)
    >>> dmp.tau, dmp.n_basis
    (2.0, 40)
    >>> bool(np.abs(rollout(dmp, n_samples=201) - stroke).max() < 1e-3)
    True
    """
    y = _points(points)
    n = y.shape[0]
    tau = _positive(tau, "tau")
    n_basis = basis_count(n) if n_basis is None else _count(n_basis, "n_basis", minimum=1)
    regularisation = _nonnegative(regularisation, "regularisation")
    stiffness = _positive(stiffness, "stiffness")
    damping = 2.0 * math.sqrt(stiffness) if damping is None else _nonnegative(damping, "damping")
    alpha_x = _positive(alpha_x, "alpha_x")
    demonstrated = _velocities(velocities)
    centres, widths = basis_functions(n_basis, alpha_x, width_factor)

    x, targets, start_velocity, goal_velocity = _targets(
        y, tau, stiffness, damping, alpha_x, demonstrated
    )
    start, values = _design_band(x, centres, widths)
    with _one_blas_thread():
        weights = _ridge(start, values, targets, regularisation, n_basis)
    return DMP(
        weights=weights,
        y0=y[0],
        goal=y[-1],
        tau=tau,
        stiffness=stiffness,
        damping=damping,
        alpha_x=alpha_x,
        centres=centres,
        widths=widths,
        n_samples=n,
        start_velocity=start_velocity,
        goal_velocity=goal_velocity,
    )


def _ridge(
    start: _FloatArray,
    values: _FloatArray,
    targets: _FloatArray,
    regularisation: float,
    n_basis: int,
) -> _FloatArray:
    """``argmin (1/n) ||Phi W - targets||^2 + regularisation ||W||^2``, one solve for all dims.

    ``Phi`` is given as a band (:func:`_design_band`); its Gram matrix is banded too (bandwidth
    ``width - 1``) and is built and factorised (Cholesky) in band storage.
    """
    n, width = values.shape
    phi = _dense(start, values, n_basis)
    if regularisation == 0:
        return np.linalg.lstsq(phi, targets, rcond=None)[0]
    banded = _banded_gram(phi, start, width)
    banded /= n
    banded[-1] += regularisation
    try:
        return scipy.linalg.solveh_banded(banded, phi.T @ targets / n, check_finite=False)
    except np.linalg.LinAlgError:  # not numerically positive definite: the same problem by lstsq
        augmented = np.vstack([phi / math.sqrt(n), math.sqrt(regularisation) * np.eye(n_basis)])
        padded = np.vstack([targets / math.sqrt(n), np.zeros((n_basis, targets.shape[1]))])
        return np.linalg.lstsq(augmented, padded, rcond=None)[0]


def _banded_gram(phi: _FloatArray, start: _FloatArray, width: int) -> _FloatArray:
    """``phi.T @ phi`` in upper band storage, ``banded[width - 1 - d, i + d] = gram[i, i + d]``.

    Row ``k`` of ``phi`` (n, n_basis) is zero outside columns ``start[k] .. start[k] + width -
    1``, so the Gram matrix has bandwidth ``width - 1``; it is built ``width`` rows at a time
    from the samples that reach them (one BLAS product per block).
    """
    n_basis = phi.shape[1]
    end = start + width
    banded = np.zeros((width, n_basis))
    for lo in range(0, n_basis, width):
        hi, far = min(lo + width, n_basis), min(lo + 2 * width, n_basis)
        if width == n_basis:  # no band: one symmetric product
            block = phi.T @ phi
        else:
            rows = np.flatnonzero((end > lo) & (start < hi))
            if rows.size and rows[-1] - rows[0] + 1 == rows.size:  # contiguous: a view
                rows = slice(rows[0], rows[-1] + 1)
            block = phi[rows, lo:hi].T @ phi[rows, lo:far]  # gram[lo:hi, lo:far]
        i, d = _band_entries(hi - lo, width, far - lo)
        banded[width - 1 - d, lo + i + d] = block[i, i + d]
    return banded


@functools.lru_cache(maxsize=16)
def _band_entries(rows: int, width: int, columns: int) -> tuple[_FloatArray, _FloatArray]:
    """Row ``i`` and diagonal ``d`` of each entry ``(i, i + d)``, ``d < width``, of a ``rows`` x
    ``columns`` block of a band (the same for every full block of :func:`_banded_gram`)."""
    i, d = np.nonzero(np.add.outer(np.arange(rows), np.arange(width)) < columns)
    i.setflags(write=False)
    d.setflags(write=False)
    return i, d
