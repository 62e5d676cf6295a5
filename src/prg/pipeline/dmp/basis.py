"""Basis functions in phase, the design matrix they make, and the forcing term ``f(x)``.

**Basis functions** are spaced evenly in time: ``c_i = exp(-alpha_x i / (N - 1))``, and their
widths follow the local spacing, ``h_i = 1 / (2 (WIDTH_FACTOR (c_i - c_{i+1}))^2)`` (the last
reuses the previous spacing), so every Gaussian covers about the same span of time.

Basis functions are local, so the design matrix is evaluated only within ``_BAND`` columns of
each sample's nearest centre (the columns left out are below ``1e-16`` of the largest; checked,
else the full matrix is used); :func:`design_matrix` is the plain dense definition.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from prg.pipeline.dmp.settings import (
    ALPHA_X,
    BASIS_MAXIMUM,
    BASIS_MINIMUM,
    BASIS_PER_100_POINTS,
    WIDTH_FACTOR,
    _FloatArray,
)
from prg.pipeline.dmp.validation import _count, _positive

_BAND = 12  # columns of the design matrix kept either side of a sample's nearest centre
_NEGLIGIBLE = math.log(1e-16)  # log of the largest activation ratio that may be left out


def basis_count(
    n_points: int,
    per_100_points: float = BASIS_PER_100_POINTS,
    minimum: int = BASIS_MINIMUM,
    maximum: int = BASIS_MAXIMUM,
) -> int:
    """Number of basis functions for a trajectory of ``n_points`` points.

    ``round(n_points * per_100_points / 100)`` clipped to ``[minimum, maximum]``. A word's point
    count grows with its length (about 100 points a letter), and so does the detail the forcing
    term must carry. The defaults (20 per 100 points, at least 20, at most 2000) give 200 basis
    functions for a 1000-point word; a 1000-point curve of twelve loops then reproduces to about
    1e-4 mm, and 100 (about eight per loop) still to about 2e-4 mm, while 75 leave 0.03 mm and 50
    leave 1.4 mm: the defaults keep a margin of about two for words with denser strokes.

    Parameters
    ----------
    n_points : int
        Number of points of the trajectory, >= 1.
    per_100_points : float
        Basis functions per 100 points, > 0.
    minimum, maximum : int
        Bounds on the result, ``1 <= minimum <= maximum``.

    Returns
    -------
    int
    """
    n_points = _count(n_points, "n_points", minimum=1)
    per_100_points = _positive(per_100_points, "per_100_points")
    minimum = _count(minimum, "minimum", minimum=1)
    maximum = _count(maximum, "maximum", minimum=minimum)
    return int(min(max(round(n_points * per_100_points / 100.0), minimum), maximum))


def basis_functions(
    n_basis: int, alpha_x: float = ALPHA_X, width_factor: float = WIDTH_FACTOR
) -> tuple[_FloatArray, _FloatArray]:
    """Centres and widths of ``n_basis`` Gaussians in phase, spaced evenly in time.

    Parameters
    ----------
    n_basis : int
        Number of basis functions, >= 1.
    alpha_x : float
        Canonical-system constant, > 0.
    width_factor : float
        Standard deviation of each Gaussian in units of the spacing to the next centre, > 0.

    Returns
    -------
    centres : ndarray, shape (n_basis,)
        ``exp(-alpha_x * linspace(0, 1, n_basis))``, decreasing (``[1.0]`` for one).
    widths : ndarray, shape (n_basis,)
        ``h_i = 1 / (2 (width_factor (c_i - c_{i+1}))^2)``; the last reuses the previous spacing;
        a single basis function gets the spacing ``1 - exp(-alpha_x)``.
    """
    n_basis = _count(n_basis, "n_basis", minimum=1)
    alpha_x = _positive(alpha_x, "alpha_x")
    width_factor = _positive(width_factor, "width_factor")
    if n_basis == 1:
        centres = np.ones(1)
        spacing = np.array([1.0 - math.exp(-alpha_x)])
    else:
        centres = np.exp(-alpha_x * np.linspace(0.0, 1.0, n_basis))
        spacing = -np.diff(centres)
        spacing = np.append(spacing, spacing[-1])
    widths = 1.0 / (2.0 * (width_factor * spacing) ** 2)
    return centres, widths


def design_matrix(x: ArrayLike, centres: ArrayLike, widths: ArrayLike) -> _FloatArray:
    """Normalised, phase-gated basis activations ``x psi_i(x) / sum_j psi_j(x)`` (dense).

    Parameters
    ----------
    x : array_like, shape (n,)
        Phase values.
    centres, widths : array_like, shape (n_basis,)
        As from :func:`basis_functions`.

    Returns
    -------
    ndarray, shape (n, n_basis)
        ``f(x) = design_matrix(x, centres, widths) @ weights``. Rows are normalised in log space,
        so they stay finite where every Gaussian underflows.
    """
    x = np.asarray(x, dtype=np.float64)
    centres = np.asarray(centres, dtype=np.float64)
    widths = np.asarray(widths, dtype=np.float64)
    return _normalised(x, x[:, None] - centres, widths)


def _normalised(x: _FloatArray, offsets: _FloatArray, widths: _FloatArray) -> _FloatArray:
    """``x psi / sum(psi)`` row by row from ``offsets = x - c`` (n, m) and the matching widths.

    Works in place on ``offsets``, which becomes the result.
    """
    offsets *= offsets
    offsets *= -widths  # log psi
    offsets -= offsets.max(axis=1, keepdims=True)
    psi = np.exp(offsets, out=offsets)
    psi *= (x / psi.sum(axis=1))[:, None]
    return psi


def _design_band(
    x: _FloatArray, centres: _FloatArray, widths: _FloatArray
) -> tuple[_FloatArray, _FloatArray]:
    """:func:`design_matrix` near each sample's largest activation: ``(start, values)``.

    ``values[k, j]`` is column ``start[k] + j`` of row ``k``; the columns left out are below
    ``1e-16`` of the row's largest (checked on the two just outside the band, else all columns
    are kept: ``start = 0``, ``values`` dense). Shapes (n,) and (n, width).
    """
    n, n_basis = x.size, centres.size
    width = 2 * _BAND + 1
    if n_basis > width:
        # the largest activation is at one of the two centres around x (centres decrease)
        above = np.clip(n_basis - np.searchsorted(centres[::-1], x), 1, n_basis - 1)
        log_left = -widths[above - 1] * (x - centres[above - 1]) ** 2
        log_right = -widths[above] * (x - centres[above]) ** 2
        peak = np.where(log_left >= log_right, above - 1, above)
        start = np.clip(peak - _BAND, 0, n_basis - width)
        top = np.maximum(log_left, log_right)
        before = np.maximum(start - 1, 0)
        after = np.minimum(start + width, n_basis - 1)
        negligible = (
            (start == 0) | (-widths[before] * (x - centres[before]) ** 2 - top < _NEGLIGIBLE)
        ) & (
            (start + width == n_basis)
            | (-widths[after] * (x - centres[after]) ** 2 - top < _NEGLIGIBLE)
        )
        if negligible.all():
            cols = start[:, None] + np.arange(width)
            return start, _normalised(x, x[:, None] - centres[cols], widths[cols])
    return np.zeros(n, dtype=np.intp), design_matrix(x, centres, widths)


def _forcing(
    x: _FloatArray, centres: _FloatArray, widths: _FloatArray, weights: _FloatArray
) -> _FloatArray:
    """``f(x) = design_matrix(x, centres, widths) @ weights`` through the band, shape (n, dims)."""
    start, values = _design_band(x, centres, widths)
    if values.shape[1] == centres.size:
        return values @ weights
    cols = start[:, None] + np.arange(values.shape[1])
    return np.column_stack([np.einsum("kj,kj->k", values, w[cols]) for w in weights.T])


def _dense(start: _FloatArray, values: _FloatArray, n_basis: int) -> _FloatArray:
    """The full (n, n_basis) design matrix from its band."""
    n, width = values.shape
    if width == n_basis:
        return values
    out = np.zeros((n, n_basis))
    flat = (np.arange(n) * n_basis + start)[:, None] + np.arange(width)
    out.ravel()[flat.ravel()] = values.ravel()
    return out
