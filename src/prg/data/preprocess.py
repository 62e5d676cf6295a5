"""Preprocessing of one-stroke character trajectories: the paper's data pipeline as pure functions.

A raw stroke (source coordinates, y down) becomes the model's trajectory modality by
:func:`preprocess_stroke`: flip y so it points up, Gaussian smoothing, resampling to ``n`` points
**equidistant along the arc** (the paper), then :func:`normalise` (centre on the mean, scale so the
largest absolute coordinate is 1, aspect ratio kept). :func:`render` draws the image modality from
the normalised trajectory.

Flat layout used everywhere a trajectory is a vector (model batches, dataset files): interleaved,
``[x1, y1, x2, y2, ..., x100, y100]`` — i.e. ``points.reshape(-1)`` of an ``(n, 2)`` array.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from prg.errors import UsageError
from prg.fields import check_fields, checked, integer, number

TRAJ_LAYOUT = "interleaved"  # flat vector = points.reshape(-1): x1, y1, x2, y2, ...


@dataclass(frozen=True)
class PreprocessSettings:
    """Settings of :func:`preprocess_stroke` (``data.preprocess`` in the Hydra config).

    Attributes
    ----------
    n_points : int
        Points after equidistant resampling (100 in the paper), at least 2.
    smooth_sigma : float
        Gaussian smoothing (see :func:`preprocess_stroke`), ``>= 0``.
    """

    n_points: int = checked(100, integer, minimum=2)
    smooth_sigma: float = checked(1.0, number, minimum=0.0)

    def __post_init__(self) -> None:
        check_fields(self)


@dataclass(frozen=True)
class ImageSettings:
    """Settings of :func:`render` (``data.image`` in the Hydra config), in pixels.

    Attributes
    ----------
    size : int
        Image side, at least 4.
    stroke_width : float
        Stroke width, ``> 0``.
    margin : float
        Empty border, ``>= 0``; ``2 * margin + stroke_width`` must leave room to draw (``< size``).
    """

    size: int = checked(28, integer, minimum=4)
    stroke_width: float = checked(2.0, number, minimum=0.0, strict=True)
    margin: float = checked(2.0, number, minimum=0.0)

    def __post_init__(self) -> None:
        check_fields(self)
        if 2 * self.margin + self.stroke_width >= self.size:  # a rule between fields: no one field
            raise UsageError(f"2*margin + stroke_width must be < size ({self.size})")


def _check_points(points: np.ndarray, name: str = "points", min_len: int = 2) -> np.ndarray:
    arr = np.asarray(points, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise UsageError(f"{name} must have shape (n, 2), got {arr.shape}")
    if arr.shape[0] < min_len:
        raise UsageError(f"{name} needs at least {min_len} points, got {arr.shape[0]}")
    if not np.all(np.isfinite(arr)):
        raise UsageError(f"{name} contains NaN or infinite values")
    return arr


def flip_y(points: np.ndarray) -> np.ndarray:
    """A copy of ``points`` (n, 2) with the y axis mirrored (tablet and font coordinates point
    down; ours point up)."""
    out = np.array(points, dtype=np.float64, copy=True)
    out[:, 1] = -out[:, 1]
    return out


def smooth(points: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian smoothing along the point sequence, endpoints held in place.

    Parameters
    ----------
    points : ndarray, shape (n, 2)
    sigma : float
        Standard deviation in samples; ``0`` returns a copy.

    Returns
    -------
    ndarray, shape (n, 2)
        Smoothed points; the first and last point equal the input's, so a stroke keeps its extent.
    """
    arr = _check_points(points, min_len=1)
    if sigma < 0:
        raise UsageError(f"smoothing sigma must be >= 0, got {sigma}")
    if sigma == 0 or arr.shape[0] < 3:
        return arr.copy()
    from scipy.ndimage import gaussian_filter1d  # here: a command that never smooths skips it

    out = gaussian_filter1d(arr, sigma=sigma, axis=0, mode="nearest")
    out[0], out[-1] = arr[0], arr[-1]
    return out


def arc_length(points: np.ndarray) -> np.ndarray:
    """Cumulative arc length at each of ``points`` (n, 2): shape (n,), ``s[0] = 0`` and ``s[-1]``
    the total length."""
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(steps)])


def resample_arclength(points: np.ndarray, n: int) -> np.ndarray:
    """Resample a polyline to ``n`` points equidistant along its arc, endpoints kept.

    Linear interpolation along the polyline; repeated points are harmless.

    Parameters
    ----------
    points : ndarray, shape (k, 2)
        At least two points, not all identical.
    n : int
        Number of output points, ``n >= 2``.

    Returns
    -------
    ndarray, shape (n, 2)

    Raises
    ------
    UsageError
        If the polyline has zero length or ``n < 2``.
    """
    arr = _check_points(points)
    if n < 2:
        raise UsageError(f"number of resampled points must be >= 2, got {n}")
    s = arc_length(arr)
    total = s[-1]
    if not total > 0:
        raise UsageError("points have zero arc length (all points identical)")
    keep = np.concatenate([[True], np.diff(s) > 0])  # drop repeats so s is strictly increasing
    s, arr = s[keep], arr[keep]
    targets = np.linspace(0.0, total, n)
    out = np.column_stack([np.interp(targets, s, arr[:, 0]), np.interp(targets, s, arr[:, 1])])
    out[0], out[-1] = arr[0], arr[-1]
    return out


def normalise(points: np.ndarray) -> np.ndarray:
    """``points`` (n, 2) centred on their mean point and scaled so that the largest absolute
    coordinate is 1: aspect ratio kept, all coordinates in ``[-1, 1]``."""
    arr = _check_points(points)
    centred = arr - arr.mean(axis=0)
    scale = np.abs(centred).max()
    if not scale > 0:
        raise UsageError("points have zero extent; cannot normalise")
    return centred / scale


def preprocess_stroke(
    stroke: np.ndarray, n_points: int = 100, smooth_sigma: float = 1.0, y_down: bool = True
) -> np.ndarray:
    """The full trajectory pipeline for one raw stroke.

    Parameters
    ----------
    stroke : ndarray, shape (k, 2)
        Raw pen-down points in source coordinates.
    n_points : int
        Points after equidistant resampling (100 in the paper).
    smooth_sigma : float
        Gaussian smoothing, in samples of an intermediate resampling to ``2 * n_points`` points
        (so the amount of smoothing does not depend on the tablet's sampling rate).
    y_down : bool
        True when the source's y axis points down (UJI tablet, Hershey fonts).

    Returns
    -------
    ndarray, shape (n_points, 2)
        Normalised trajectory, y up.

    Raises
    ------
    UsageError
        For a stroke of zero length, or when its points resampled along the arc coincide (up to
        ``1e-9`` of the stroke's extent): a closed stroke resampled to 2 points, or a stroke going
        back and forth that the samples happen to catch at one point. No normalisation can scale
        those, and scaling their rounding noise up to the unit box would be garbage.
    """
    arr = _check_points(stroke, name="stroke")
    if y_down:
        arr = flip_y(arr)
    extent = np.ptp(arr, axis=0).max()
    dense = _resample_spread(arr, 2 * n_points, extent)
    dense = smooth(dense, smooth_sigma)
    return normalise(_resample_spread(dense, n_points, extent))


def _resample_spread(points: np.ndarray, n: int, extent: float) -> np.ndarray:
    """:func:`resample_arclength`, refusing samples that coincide (``preprocess_stroke``)."""
    out = resample_arclength(points, n)
    if not np.ptp(out, axis=0).max() > 1e-9 * extent:
        raise UsageError(
            f"stroke: its {n} points resampled along the arc coincide (a closed or back-and-forth "
            "stroke needs more points); cannot normalise"
        )
    return out


def render(
    points: np.ndarray, size: int = 28, stroke_width: float = 2.0, margin: float = 2.0
) -> np.ndarray:
    """Draw a trajectory as an anti-aliased grey image.

    The polyline is scaled (aspect ratio kept) so its bounding box fits inside the image minus
    ``margin`` and half the stroke width on every side, and centred. A pixel's intensity falls
    linearly from 1 to 0 over one pixel at the stroke's edge (distance ``stroke_width / 2`` from
    the polyline), which gives anti-aliasing with round caps and joins.

    Parameters
    ----------
    points : ndarray, shape (n, 2)
        Trajectory, y up (any scale).
    size : int
        Image side in pixels.
    stroke_width : float
        Stroke width in pixels (fixed relative to the image, whatever the letter's extent).
    margin : float
        Empty border in pixels.

    Returns
    -------
    ndarray, shape (size, size), float32
        Ink intensity in ``[0, 1]``; row 0 is the top of the image.
    """
    return render_batch(np.asarray(points)[None], size, stroke_width, margin)[0]


def render_batch(
    trajectories: np.ndarray,
    size: int = 28,
    stroke_width: float = 2.0,
    margin: float = 2.0,
    chunk: int = 512,
) -> np.ndarray:
    """Vectorised :func:`render` over many trajectories.

    The distance from a pixel to the polyline is taken as its distance to the nearest of the
    polyline's points resampled every ``_RENDER_STEP`` pixels, evaluated only in a small window of
    pixels around each point. At a true distance ``d`` it is at most ``sqrt(d^2 + 0.125^2) - d``
    too large: below 0.016 px where a 2-pixel stroke's ink is not clipped (``d >= 0.5``).

    Parameters
    ----------
    trajectories : ndarray, shape (b, n, 2)
    size, stroke_width, margin : see :func:`render`
    chunk : int
        Trajectories per vectorised step (bounds memory).

    Returns
    -------
    ndarray, shape (b, size, size), float32
    """
    trajs = np.asarray(trajectories, dtype=np.float64)
    if trajs.ndim != 3 or trajs.shape[2] != 2 or trajs.shape[1] < 2:
        raise UsageError(f"trajectories must have shape (b, n>=2, 2), got {trajs.shape}")
    if not np.all(np.isfinite(trajs)):
        raise UsageError("trajectories contain NaN or infinite values")
    if size < 4 or stroke_width <= 0 or margin < 0 or 2 * margin + stroke_width >= size:
        raise UsageError(
            f"render settings size={size}, stroke_width={stroke_width}, margin={margin} leave no "
            "room to draw: need size >= 4, stroke_width > 0, margin >= 0, 2*margin+width < size"
        )
    reach = stroke_width / 2 + 0.5  # beyond this distance a pixel gets no ink
    radius = int(np.ceil(reach))
    offsets = np.arange(-radius, radius + 1)
    win_r, win_c = (a.reshape(-1) for a in np.meshgrid(offsets, offsets, indexing="ij"))
    out = np.empty((trajs.shape[0], size, size), dtype=np.float32)
    for start in range(0, trajs.shape[0], chunk):
        img_pts = _to_image_coords(trajs[start : start + chunk], size, stroke_width, margin)
        owner, dense = _dense_points(img_pts, _RENDER_STEP)  # (m,), (m, 2) as (col, row)
        rows = np.floor(dense[:, 1]).astype(np.int64)[:, None] + win_r[None]
        cols = np.floor(dense[:, 0]).astype(np.int64)[:, None] + win_c[None]
        dist = np.hypot(cols + 0.5 - dense[:, :1], rows + 0.5 - dense[:, 1:])
        inside = (rows >= 0) & (rows < size) & (cols >= 0) & (cols < size) & (dist < reach)
        flat = (owner[:, None] * size + rows) * size + cols
        nearest = np.full(len(img_pts) * size * size, np.inf)
        np.minimum.at(nearest, flat[inside], dist[inside])
        ink = np.clip(reach - nearest, 0.0, 1.0)
        out[start : start + chunk] = ink.reshape(-1, size, size)
    return out


_RENDER_STEP = 0.25  # pixels between the points at which the polyline is sampled for rendering


def _to_image_coords(trajs: np.ndarray, size: int, width: float, margin: float) -> np.ndarray:
    lo, hi = trajs.min(axis=1), trajs.max(axis=1)  # (b, 2)
    extent = np.maximum((hi - lo).max(axis=1), 1e-12)  # (b,)
    usable = size - 2 * margin - width
    scale = usable / extent
    centre = (lo + hi) / 2
    pts = (trajs - centre[:, None, :]) * scale[:, None, None]
    pts[..., 1] = -pts[..., 1]  # y up -> image rows down
    return pts + size / 2


def _dense_points(polylines: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Points every ``step`` along each segment of each polyline (b, n, 2).

    Returns the owning polyline index (m,) and the points (m, 2), segment ends included.
    """
    a = polylines[:, :-1, :].reshape(-1, 2)
    ab = (polylines[:, 1:, :] - polylines[:, :-1, :]).reshape(-1, 2)
    owner_seg = np.repeat(np.arange(polylines.shape[0]), polylines.shape[1] - 1)
    counts = np.ceil(np.hypot(ab[:, 0], ab[:, 1]) / step).astype(np.int64) + 1  # >= 1 per segment
    seg = np.repeat(np.arange(len(a)), counts)
    first = np.cumsum(counts) - counts
    frac = (np.arange(counts.sum()) - first[seg]) / np.maximum(counts[seg] - 1, 1)
    points = a[seg] + frac[:, None] * ab[seg]
    return owner_seg[seg], points
