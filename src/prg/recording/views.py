"""What both recorders share in the viewer: the y-flip, the framing, and animated entities.

Coordinates
    Word and page coordinates are centimetres with y up, but Rerun's 2D views draw y down and
    ignore view coordinates in 2D. Every 2D position is therefore logged as ``(x, -y)``
    (:func:`flip`): the word reads upright in the viewer, and a reader of the file recovers
    centimetres, y up, by negating the second coordinate (:data:`Y_SIGN`).

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
