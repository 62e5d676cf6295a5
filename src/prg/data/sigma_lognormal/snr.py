"""The point signal-to-noise ratio by which a fit's reconstruction is judged."""

from __future__ import annotations

import math

import numpy as np


def snr_db(points: np.ndarray, reconstruction: np.ndarray) -> float:
    """Signal-to-noise ratio of a reconstruction, in dB.

    Parameters
    ----------
    points, reconstruction : ndarray, shape (n, 2)

    Returns
    -------
    float
        ``10 log10(sum ||x - mean(x)||^2 / sum ||x - x_hat||^2)``; capped at 200 dB for a perfect
        reconstruction.
    """
    signal = float(np.sum((points - points.mean(axis=0)) ** 2))
    noise = float(np.sum((points - reconstruction) ** 2))
    if not signal > 0:
        return 0.0
    return float(min(200.0, 10.0 * math.log10(signal / max(noise, signal * 1e-20))))
