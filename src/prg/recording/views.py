"""What both recorders share in the viewer: the y-flip, the framing of views, animated entities.

Coordinates
    Word and page coordinates are centimetres with y up, but Rerun's 2D views draw y down and
    ignore view coordinates in 2D. Every 2D position is therefore logged as ``(x, -y)``
    (:func:`flip`): the word reads upright in the viewer, and a reader of the file recovers
    centimetres, y up, by negating the second coordinate (:data:`Y_SIGN`).

Framing
    The default blueprints open every view on its data: 2D views get bounds around their points
    with a margin (:func:`framing`), 3D views an eye placed so that the points fill Rerun's field
    of view (:func:`framing_eye`).

Animation
    A moving point is one row per frame; a growing path is one two-point segment per step,
    which the default blueprint accumulates with a visible time range from the start to the
    cursor (:func:`accumulated`, Rerun's idiom for trails), so the data grow linearly with the
    steps. Each is a static style (colour, radius, draw order) plus one
    :meth:`~rerun.RecordingStream.send_columns` call (:func:`log_columns`).
"""

from __future__ import annotations

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

Y_SIGN = np.array([1.0, -1.0])  # word (x, y up) -> Rerun 2D (x, y down), and back
EYE_FOV_Y_DEG = 55.0  # Rerun's 3D eye (re_view_spatial's Eye::DEFAULT_FOV_Y): no blueprint sets it
EYE_NEAR_M = 0.035  # the eye keeps at least this far in front of every framed point


def flip(points: np.ndarray) -> np.ndarray:
    """``points`` (..., 2) as float64 with y negated: (x, y up) <-> (x, y down)."""
    return np.asarray(points, dtype=np.float64) * Y_SIGN


def framing(points: np.ndarray, margin: float = 0.15) -> rrb.VisualBounds2D:
    """2D view bounds around ``points`` (already y-flipped) with a relative margin, so the
    viewer opens on the whole word rather than on its own guess."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    low, high = pts.min(axis=0), pts.max(axis=0)
    pad = margin * max(float((high - low).max()), 1.0)
    return rrb.VisualBounds2D(
        x_range=[low[0] - pad, high[0] + pad], y_range=[low[1] - pad, high[1] + pad]
    )


def framing_eye(
    points: np.ndarray, looking_from: np.ndarray, margin: float = 0.1, aspect: float = 1.0
) -> rrb.EyeControls3D:
    """A 3D view's eye looking at ``points`` (world, shape (n, 3)) from the direction
    ``looking_from``, as close as Rerun's field of view lets it while every point stays inside
    it with a relative margin: the viewer opens on them rather than on its own guess.

    ``aspect`` is the least width over height the view will have (Rerun's field of view,
    :data:`EYE_FOV_Y_DEG`, is vertical; it is ``aspect`` times wider across). The eye looks
    along ``-looking_from`` (z up) at the middle of the points' picture and orbits there.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    forward = -np.asarray(looking_from, dtype=np.float64)
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    middle = (pts.min(axis=0) + pts.max(axis=0)) / 2
    depth = (pts - middle) @ forward
    half_y = np.tan(np.radians(EYE_FOV_Y_DEG) / 2) / (1.0 + margin)
    across = [
        ((pts - middle) @ axis, half) for axis, half in ((right, half_y * aspect), (up, half_y))
    ]
    # the eye at `shift` across and `distance` back from `middle` holds a point of offset x and
    # depth z when |x - shift| <= half * (z + distance): the least distance that leaves a shift
    # for every point, then the shift in the middle of those left
    distance = max(
        *[(np.max(x / half - depth) + np.max(-x / half - depth)) / 2 for x, half in across],
        np.max(EYE_NEAR_M - depth),
    )
    target = middle.copy()
    for axis, (x, half) in zip((right, up), across):
        reach = half * (depth + distance)
        target += axis * (np.max(x - reach) + np.min(x + reach)) / 2
    return rrb.EyeControls3D(
        position=(target - forward * distance).tolist(),
        look_target=target.tolist(),
        eye_up=(0.0, 0.0, 1.0),
    )


def accumulated(timeline: str, archetype: type = rr.LineStrips2D) -> list:
    """Blueprint overrides that draw an entity's rows from the start of ``timeline`` to the
    cursor with ``archetype``'s visualizer: a path grows as the time cursor moves."""
    trail = rrb.VisibleTimeRanges(
        timeline=timeline,
        start=rrb.TimeRangeBoundary.infinite(),
        end=rrb.TimeRangeBoundary.cursor_relative(),
    )
    return [trail, archetype.from_fields().visualizer()]


def segments(points: np.ndarray) -> np.ndarray:
    """The steps of a path as two-point strips, ``(points[i - 1], points[i])``: shape
    (n - 1, 2, dims)."""
    return np.stack([points[:-1], points[1:]], axis=1)


def log_columns(
    rec: rr.RecordingStream,
    entity: str,
    style,
    timeline: str,
    times: np.ndarray,
    columns,
    *,
    strict: bool | None = None,
) -> None:
    """Log ``style`` (an archetype's ``from_fields``: colours, radii, draw order) statically
    on ``entity``, then, if there are any, its rows ``columns`` at ``times`` (seconds) on the
    duration timeline ``timeline`` in one :meth:`~rerun.RecordingStream.send_columns` call."""
    rec.log(entity, style, static=True, strict=strict)
    if len(times):
        rec.send_columns(
            entity,
            indexes=[rr.TimeColumn(timeline, duration=times)],
            columns=columns,
            strict=strict,
        )
