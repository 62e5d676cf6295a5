"""Time stamps for equidistant points from the two-thirds power law.

Preprocessed trajectories are equidistant along the arc, so they carry no speed information.
:func:`power_law_timestamps` assigns times with the **two-thirds power law** of human movement
(tangential speed ``v = K kappa^(-1/3)``, i.e. angular speed proportional to ``kappa^(2/3)``).
Curvature ``kappa`` is the turning angle per unit arc length at each vertex, smoothed with a
Gaussian (``smooth`` samples) and expressed relative to the stroke length ``L`` (``kappa * L`` is
scale free: a full circle has ``2 pi``); it is clipped to ``curvature_range`` so straight parts do
not get infinite speed and sharp corners do not stop the pen completely. The speed is also
multiplied by a smooth onset/offset envelope (the pen accelerates from rest and decelerates to
rest over the first and last ``ramp`` fraction of the arc, from ``ramp_floor`` times the cruise
speed), which matches the bell-shaped speed profiles that lognormals describe. Times are scaled so
the stroke lasts ``total_time``.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d

from prg.data.sigma_lognormal.params import _TINY


def power_law_timestamps(
    points: np.ndarray,
    total_time: float = 1.0,
    smooth: float = 2.0,
    curvature_range: tuple[float, float] = (2.0, 60.0),
    ramp: float = 0.1,
    ramp_floor: float = 0.3,
) -> np.ndarray:
    """Time stamps for equidistant points from the two-thirds power law.

    Parameters
    ----------
    points : ndarray, shape (n, 2)
        A stroke; any spacing (the law is applied per segment).
    total_time : float
        Duration of the stroke.
    smooth : float
        Gaussian smoothing of the curvature, in samples.
    curvature_range : (float, float)
        Clipping range of the length-relative curvature ``kappa * L``.
    ramp : float
        Fraction of the arc length over which the pen accelerates from / decelerates to
        ``ramp_floor`` times its cruise speed (``0`` disables the envelope).
    ramp_floor : float
        Relative speed at the very first and last point, in ``(0, 1]``.

    Returns
    -------
    ndarray, shape (n,)
        Strictly increasing, ``t[0] = 0``, ``t[-1] = total_time``.
    """
    pts = np.asarray(points, dtype=np.float64)
    n = pts.shape[0]
    if n < 2:
        return np.zeros(n)
    seg = np.diff(pts, axis=0)
    ds = np.linalg.norm(seg, axis=1)
    length = float(ds.sum())
    if not (np.isfinite(length) and length > 0):
        return np.linspace(0.0, total_time, n)
    s = np.concatenate([[0.0], np.cumsum(ds)]) / length
    kappa_l = np.full(n, curvature_range[0])
    if n >= 3:
        heading = np.arctan2(seg[:, 1], seg[:, 0])
        turn = np.abs(np.angle(np.exp(1j * np.diff(heading))))
        local = 0.5 * (ds[:-1] + ds[1:])
        kappa_l[1:-1] = turn / np.maximum(local, _TINY * length) * length
        kappa_l[0], kappa_l[-1] = kappa_l[1], kappa_l[-2]
        if smooth > 0:
            kappa_l = gaussian_filter1d(kappa_l, smooth, mode="nearest")
    kappa_l = np.clip(kappa_l, *curvature_range)
    vertex_speed = kappa_l ** (-1.0 / 3.0)
    if ramp > 0:
        edge = np.clip(np.minimum(s, 1.0 - s) / ramp, 0.0, 1.0)
        smoothstep = edge * edge * (3.0 - 2.0 * edge)
        vertex_speed = vertex_speed * (ramp_floor + (1.0 - ramp_floor) * smoothstep)
    seg_speed = 0.5 * (vertex_speed[:-1] + vertex_speed[1:])
    dt = np.maximum(ds, _TINY * length) / seg_speed
    t = np.concatenate([[0.0], np.cumsum(dt)])
    return t * (total_time / t[-1])
