"""Helpers shared by the tests that were split out of tests/test_properties.py."""

from __future__ import annotations

import math
import os

import numpy as np
from hypothesis import HealthCheck, assume, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

SCALE = float(os.environ.get("PRG_PROPERTY_SCALE", "1"))


def examples(n: int) -> settings:
    """``n`` examples (times ``PRG_PROPERTY_SCALE``); no deadline and no too-slow health check,
    which only measure how busy a shared machine is."""
    return settings(
        max_examples=max(1, round(n * SCALE)),
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow],
    )


# ============================================================================= strategies and helpers

unit = st.floats(-1.0, 1.0, allow_nan=False, allow_infinity=False)


# coarse values make repeated points, zero-length segments, collinear runs and retraces common
grid = st.integers(-4, 4).map(lambda v: v / 4)


def log_uniform(lo_exp: float, hi_exp: float) -> st.SearchStrategy[float]:
    return st.floats(lo_exp, hi_exp).map(lambda e: 10.0**e)


@st.composite
def polylines(draw, min_points: int = 2, max_points: int = 40, max_offset: float = 1e3):
    """An arbitrary polyline: ``offset + scale * shape``, ``shape`` in the unit square with extent.

    Shapes are free points (continuous or on a coarse grid), collinear points (a straight stroke
    walked back and forth), or free points each repeated a few times. ``scale`` spans 1e-3 to 1e4
    and the offset up to ``max_offset`` times the scale.
    """
    n = draw(st.integers(min_points, max_points))
    kind = draw(st.sampled_from(["free", "grid", "collinear", "repeated"]))
    if kind == "collinear":
        t = draw(arrays(np.float64, n, elements=st.one_of(grid, unit)))
        angle = draw(st.floats(0.0, 2 * math.pi))
        shape = np.outer(t, [math.cos(angle), math.sin(angle)])
    elif kind == "repeated":  # pauses: each point repeated 1-3 times, padded to min_points
        base = draw(arrays(np.float64, (max(2, n // 2), 2), elements=unit))
        reps = draw(arrays(np.int64, len(base), elements=st.integers(1, 3)))
        shape = np.repeat(base, reps, axis=0)[:max_points]
        shape = np.concatenate(
            [shape, np.repeat(shape[-1:], max(0, min_points - len(shape)), axis=0)]
        )
    else:
        elements = grid if kind == "grid" else unit
        shape = draw(arrays(np.float64, (n, 2), elements=elements))
    assume(np.ptp(shape, axis=0).max() >= 0.05)
    scale = draw(log_uniform(-3, 4))
    offset = draw(arrays(np.float64, 2, elements=st.floats(-max_offset, max_offset)))
    return offset * scale + shape * scale


def steps(path: np.ndarray) -> np.ndarray:
    """Lengths of the segments of a polyline (n, 2)."""
    d = np.diff(path, axis=0)
    return np.hypot(d[:, 0], d[:, 1])


# ============================================================================= DMP

# Reproduction bounds, in units of the demonstration's largest step. Measured worst cases over
# several thousand examples steered by hypothesis.target: 1.62, 0.15 and 2.7.
STEP_RATIO = 2.0  # the rollout's largest step


END_ERROR = 0.5  # distance from the rollout's end to the goal


DEVIATION = 6.0  # largest distance between rollout and demonstration at the same sample


def walked(path: np.ndarray, n: int) -> np.ndarray:
    """``n`` samples, uniform in time, of a pen walking ``path`` with a minimum-jerk time course
    (at rest at both ends)."""
    t = np.linspace(0.0, 1.0, n)
    at = (10 * t**3 - 15 * t**4 + 6 * t**5) * steps(path).sum()
    arc = np.concatenate([[0.0], np.cumsum(steps(path))])
    return np.column_stack([np.interp(at, arc, path[:, 0]), np.interp(at, arc, path[:, 1])])


@st.composite
def demonstrations(draw):
    """A pen motion sampled uniformly in time: a polyline (possibly closed, goal = start) walked
    with a minimum-jerk time course, so it starts and ends at rest, as the DMP expects.

    At least 5 samples per segment of the polyline: coarser sampling does not start at rest
    (the first finite differences see the motion already going; the DMP module documents the
    transient this leaves) and can miss the motion altogether (samples of a back-and-forth
    stroke that all land on one point). Scales 1e-3 to 1e4, offsets up to 1e3 times the scale,
    3 to 600 samples; the examples below add a long and a nearly constant one.
    """
    path = draw(polylines(max_points=10))
    if draw(st.booleans()) and path.shape[0] > 2:
        path = np.concatenate([path, path[:1]])  # goal = start
    demo = walked(path, draw(st.integers(max(3, 5 * (path.shape[0] - 1)), 600)))
    assume(steps(demo).max() > 0)
    return demo
