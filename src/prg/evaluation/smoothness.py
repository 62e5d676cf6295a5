"""How jittery a trajectory is: roughness = sum of ``|second differences|`` / arc length.

A letter's 100 points are equidistant along the arc after preprocessing, so a smooth stroke has
second differences close to zero (they grow only with curvature), while a decoder that has not
learnt the coordinates' correlations adds point-to-point noise that shows up here long before it
changes the letter's class. The measure is scale-free (both sums scale with the letter), so
decoded letters compare directly with the test split's letters: the *roughness ratio* is the
median over decoded letters divided by the median over the test split.
"""

from __future__ import annotations

import numpy as np


def roughness(traj: np.ndarray) -> np.ndarray:
    """Roughness of each trajectory.

    Parameters
    ----------
    traj : array, shape (..., 200) interleaved ``x1, y1, ...`` or (..., n, 2)

    Returns
    -------
    array, shape (...)
        ``sum_i |p[i+1] - 2 p[i] + p[i-1]| / sum_i |p[i+1] - p[i]|`` (Euclidean norms); NaN for a
        trajectory with no length.
    """
    points = np.asarray(traj, dtype=np.float64)
    if points.shape[-1] != 2:
        points = points.reshape(*points.shape[:-1], -1, 2)
    second = np.linalg.norm(np.diff(points, n=2, axis=-2), axis=-1).sum(-1)
    length = np.linalg.norm(np.diff(points, axis=-2), axis=-1).sum(-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(length > 0, second / length, np.nan)


def median_roughness(traj: np.ndarray) -> float:
    """Median :func:`roughness` over trajectories with a length (NaN when none has one)."""
    values = roughness(traj).ravel()
    values = values[~np.isnan(values)]
    return float(np.median(values)) if values.size else float("nan")


def roughness_ratio(decoded: np.ndarray, reference: np.ndarray) -> float:
    """Median roughness of ``decoded`` over the median roughness of ``reference`` (NaN when the
    reference's median is 0 or undefined)."""
    ref = median_roughness(reference)
    return median_roughness(decoded) / ref if ref > 0 else float("nan")
