"""The pen's motion plan: where the pen tip should be, when, and whether it should ink.

:func:`plan_motion` turns a word's DMP rollout (already placed on the paper, in cm) into
timed pen-tip waypoints in the paper frame:

1. **approach** from the home position (the pen tip in the rest posture) to above the first
   stroke's start, ``lift_cm`` over the paper (a minimum-jerk straight line);
2. per pen-down **stroke** (a run of rollout samples that are not pen-up travel between
   words): **lower** vertically onto the paper, **dwell** there, **write** the rollout
   samples at the DMP's own timing, **lift** vertically;
3. between strokes, **travel** along the rollout's pen-up samples at ``lift_cm`` (DMP timing);
4. **retreat** from above the last point back home.

Everything is a pure function of arrays; :class:`MotionPlan` holds the result.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prg.errors import UsageError
from prg.pipeline.timing import min_jerk
from prg.sim.geometry import runs
from prg.sim.settings import MotionSettings  # re-exported

__all__ = ["PHASES", "MotionPlan", "MotionSettings", "plan_motion"]

PHASES = ("approach", "lower", "dwell", "write", "lift", "travel", "retreat")
"""Phase names; :attr:`MotionPlan.phase` holds indices into this tuple."""


@dataclass(frozen=True)
class MotionPlan:
    """Timed pen-tip waypoints in the paper frame.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Seconds from the start, strictly increasing.
    tip : ndarray, shape (n, 3)
        ``(x, y, height)`` of the pen tip in cm (paper frame).
    pen_down : ndarray of bool, shape (n,)
        True on the writing samples (the commanded ink).
    stroke : ndarray of int, shape (n,)
        Stroke index for lower/dwell/write/lift samples, ``-1`` elsewhere.
    phase : ndarray of int, shape (n,)
        Index into :data:`PHASES`.
    """

    t: NDArray[np.float64]
    tip: NDArray[np.float64]
    pen_down: NDArray[np.bool_]
    stroke: NDArray[np.int64]
    phase: NDArray[np.int64]

    @property
    def n_strokes(self) -> int:
        return int(self.stroke.max()) + 1 if len(self.stroke) else 0

    @property
    def duration_s(self) -> float:
        return float(self.t[-1])

    def strokes(self) -> list[NDArray[np.float64]]:
        """The commanded pen-down strokes, each ``(n_k, 2)`` in cm."""
        return [self.tip[(self.stroke == k) & self.pen_down, :2] for k in range(self.n_strokes)]

    def pen_step_cm(self) -> float:
        """Longest step between consecutive commanded pen-down samples of a stroke (cm)."""
        steps = [np.linalg.norm(np.diff(s, axis=0), axis=1) for s in self.strokes() if len(s) > 1]
        return float(max(s.max() for s in steps)) if steps else 0.0


def _segment(start: ArrayLike, end: ArrayLike, duration: float, dt: float) -> NDArray[np.float64]:
    """Minimum-jerk straight line from ``start`` to ``end`` (both (3,)), ``dt``-spaced samples
    (the first, ``start``, included)."""
    n = max(2, math.ceil(duration / dt) + 1)
    s = min_jerk(n)[:, None]
    a, b = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    return a + s * (b - a)


def plan_motion(
    samples_cm: ArrayLike,
    t_s: ArrayLike,
    pen_down: ArrayLike,
    home_cm: ArrayLike,
    settings: MotionSettings,
    dt: float,
) -> MotionPlan:
    """Build the pen's waypoints around a placed word.

    Parameters
    ----------
    samples_cm : array_like, shape (n, 2)
        The word's DMP rollout placed on the paper (cm, paper frame).
    t_s : array_like, shape (n,)
        Its times (s), increasing, from 0.
    pen_down : array_like of bool, shape (n,)
        False for the pen-up travel between words
        (:func:`prg.sim.geometry.pen_down_samples`).
    home_cm : array_like, shape (3,)
        The pen tip's home position (paper frame, cm), where the motion starts and ends.
    settings : MotionSettings
    dt : float
        Waypoint spacing (s) of the approach, lower, dwell, lift and retreat moves.

    Returns
    -------
    MotionPlan
    """
    pts = np.asarray(samples_cm, dtype=np.float64)
    times = np.asarray(t_s, dtype=np.float64)
    down = np.asarray(pen_down, dtype=bool)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 2 or times.shape != (len(pts),):
        raise UsageError(f"samples must have shape (n >= 2, 2) with n times, got {pts.shape}")
    if not down.any():
        raise UsageError("the word has no pen-down samples: nothing to write")
    home = np.asarray(home_cm, dtype=np.float64)
    up = settings.lift_cm
    t: list[NDArray] = []
    tip: list[NDArray] = []
    phase: list[NDArray] = []
    stroke: list[NDArray] = []
    ink: list[NDArray] = []
    clock = 0.0

    def add(points: NDArray, durations: NDArray, name: str, k: int, inks: bool) -> None:
        """Append ``points`` at ``clock + durations`` (``durations[0]`` = 0 is the previous
        sample's time, so the first point is dropped when it repeats it)."""
        nonlocal clock
        keep = slice(1, None) if tip else slice(None)
        if not tip:
            durations = durations - durations[0]
        t.append(clock + durations[keep])
        tip.append(points[keep])
        phase.append(np.full(len(points[keep]), PHASES.index(name)))
        stroke.append(np.full(len(points[keep]), k))
        ink.append(np.full(len(points[keep]), inks))
        clock = float(t[-1][-1]) if len(t[-1]) else clock

    def move(start, end, duration: float, name: str, k: int = -1) -> None:
        seg = _segment(start, end, duration, dt)
        add(seg, np.linspace(0.0, duration, len(seg)), name, k, False)

    pieces = runs(down)
    first = np.append(pts[pieces[0][0]], up)
    add(home[None], np.zeros(1), "approach", -1, False)
    move(home, first, settings.approach_s, "approach")
    for k, (start, stop) in enumerate(pieces):
        above = np.append(pts[start], up)
        on = np.append(pts[start], 0.0)
        if k > 0:  # travel at lift height along the pen-up samples between the strokes
            prev = pieces[k - 1][1] - 1
            between = np.column_stack([pts[prev : start + 1], np.full(start + 1 - prev, up)])
            add(between, times[prev : start + 1] - times[prev], "travel", -1, False)
        move(above, on, settings.lower_s, "lower", k)
        if settings.dwell_s > 0:
            n = max(2, math.ceil(settings.dwell_s / dt) + 1)
            add(np.repeat(on[None], n, 0), np.linspace(0, settings.dwell_s, n), "dwell", k, False)
        written = np.column_stack([pts[start:stop], np.zeros(stop - start)])
        add(
            np.concatenate([on[None], written]),
            np.concatenate([[0.0], times[start:stop] - times[start] + dt]),
            "write",
            k,
            True,
        )
        last = np.append(pts[stop - 1], 0.0)
        move(last, np.append(pts[stop - 1], up), settings.lift_s, "lift", k)
    move(np.append(pts[pieces[-1][1] - 1], up), home, settings.approach_s, "retreat")
    return MotionPlan(
        t=np.concatenate(t),
        tip=np.concatenate(tip),
        pen_down=np.concatenate(ink),
        stroke=np.concatenate(stroke).astype(np.int64),
        phase=np.concatenate(phase).astype(np.int64),
    )
