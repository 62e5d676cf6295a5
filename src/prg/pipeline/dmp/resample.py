"""Resampling a demonstration taken at irregular times onto the uniform grid a fit needs."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from prg.errors import UsageError
from prg.pipeline.dmp.settings import _FloatArray
from prg.pipeline.dmp.validation import _count, _finite, _points


def uniform_in_time(
    points: ArrayLike, times: ArrayLike, n_samples: int | None = None
) -> tuple[_FloatArray, float]:
    """A demonstration sampled at irregular ``times`` (a pen on a tablet or a browser canvas),
    resampled uniformly in time for :func:`fit_dmp`.

    Samples that share a time are averaged into one (a browser can deliver two pointer events in
    the same millisecond), then a cubic spline through the rest (``scipy.interpolate``,
    not-a-knot ends, which leave the end velocities free) is evaluated at ``n_samples`` points
    evenly spaced from the first time to the last. The spline keeps the velocities and
    accelerations that the forcing targets are made of; linear interpolation would put a corner
    at every original sample.

    Parameters
    ----------
    points : array_like, shape (n, dims)
        Positions, finite.
    times : array_like, shape (n,)
        Their times, finite and non-decreasing, spanning more than zero.
    n_samples : int, optional
        Number of uniform samples, >= 3; default ``n``.

    Returns
    -------
    uniform : ndarray, shape (n_samples, dims)
        The positions at the uniform times; the first and last equal the first and last
        (time-averaged) samples.
    duration : float
        ``times[-1] - times[0]``: the ``tau`` to fit them with.
    """
    from scipy.interpolate import CubicSpline  # only here: scipy.interpolate costs an import

    y = _points(points)
    t = _finite(times, "times", ndim=1)
    if t.shape != (y.shape[0],):
        raise UsageError(f"times: expected shape ({y.shape[0]},) like points, got {t.shape}")
    if np.any(np.diff(t) < 0):
        raise UsageError("times: expected non-decreasing values")
    n = y.shape[0] if n_samples is None else _count(n_samples, "n_samples", minimum=3)
    unique, first = np.unique(t, return_index=True)
    if unique.size < 3:
        raise UsageError(f"times: expected at least 3 distinct times, got {unique.size}")
    counts = np.diff(np.append(first, t.size))
    merged = np.add.reduceat(y, first, axis=0) / counts[:, None]
    grid = np.linspace(unique[0], unique[-1], n)
    uniform = CubicSpline(unique, merged)(grid)
    uniform[0], uniform[-1] = merged[0], merged[-1]
    return uniform, float(unique[-1] - unique[0])
