"""A word's timed pen motion, sampled: what ``prg-write`` saves as ``motion.csv`` and what the
simulated robot (:func:`prg.sim.simulate_word`) and the plotter export follow.

:func:`word_samples` is the whole motion every ``dt`` seconds: the body's DMP rollout, then each
delayed stroke (:mod:`prg.pipeline.marks`) and the pen-up travel to it
(:func:`prg.pipeline.timing.delayed_samples`), with a pen-down flag per sample
(:func:`pen_down_samples`: up on the travel between words). Pure functions on arrays: nothing
here imports the simulator (:mod:`prg.sim` re-exports them).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prg.errors import UsageError

if TYPE_CHECKING:
    from prg.pipeline.word import WordTrajectory

__all__ = [
    "MAX_WRITING_S",
    "arc_length",
    "arc_progress",
    "pen_down_samples",
    "word_samples",
]

_Float = NDArray[np.float64]

MAX_WRITING_S = 600.0  # seconds of writing at most (a 64-letter line takes about 140 s)


def _check_duration(word: WordTrajectory, seconds: float, tempo: float) -> None:
    if not seconds <= MAX_WRITING_S:
        raise UsageError(
            f"word {word.text[:40]!r} takes {seconds:.0f} s to write at tempo={tempo:g}: accepted "
            f"are at most {MAX_WRITING_S:.0f} s of writing; lower tempo or write fewer letters"
        )


def word_samples(
    word: WordTrajectory, dt: float, tempo: float = 1.0
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """The word's motion, sampled every ``dt`` seconds: the body's DMP rollout, then each delayed
    stroke and the pen-up travel to it (:func:`prg.pipeline.timing.stroke_samples`).

    Parameters
    ----------
    word : WordTrajectory
        With ``word.dmp`` (from ``prg-write``; fitted to the body); without one, the body's
        points are followed at ``word.speed_cm_s`` with 0.3 s speed ramps.
    dt : float
        Sample spacing (s), about; each part's duration is divided evenly.
    tempo : float
        Multiplies the duration.

    Returns
    -------
    samples : ndarray, shape (n, 2)
        Centimetres, the word's own frame.
    t : ndarray, shape (n,)
        Seconds from 0, increasing.
    pen_down : ndarray of bool, shape (n,)
        False on the pen-up travel between words and to the delayed strokes.
    """
    from prg.pipeline.timing import delayed_samples, rest_to_rest_samples

    body = word.points[: word.body_end]
    after_xy, after_t, after_down = delayed_samples(word, dt, tempo)
    after_s = float(after_t[-1]) if len(after_t) else 0.0
    dmp = word.dmp
    if dmp is not None:
        from prg.pipeline.dmp import rollout

        if dmp.dims != 2:
            raise UsageError(f"word {word.text!r}: the DMP must be 2-D, it has {dmp.dims} dims")
        tau = dmp.tau * tempo
        _check_duration(word, tau + after_s, tempo)
        samples = rollout(dmp, tau=tau, dt=dt)
    else:
        body_s = float(np.linalg.norm(np.diff(body, axis=0), axis=1).sum()) / word.speed_cm_s
        _check_duration(word, body_s * tempo + after_s, tempo)
        samples, tau = rest_to_rest_samples(body, word.speed_cm_s, 0.3, 1 / (dt * tempo))
        tau *= tempo
    t = np.linspace(0.0, tau, len(samples))
    down = pen_down_samples(body, word.segment[: word.body_end], word.segment_kinds, samples)
    return (
        np.concatenate([samples, after_xy]),
        np.concatenate([t, tau + after_t]),
        np.concatenate([down, after_down]),
    )


# ----------------------------------------------------------------------------- paths


def arc_length(points: ArrayLike) -> _Float:
    """Cumulative arc length of a polyline, shape (n,), starting at 0."""
    pts = np.asarray(points, dtype=np.float64)
    steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(steps)])


def arc_progress(path: ArrayLike, samples: ArrayLike) -> _Float:
    """Arc length along ``path`` of each sample of a motion that follows it in order.

    Each sample is projected onto the polyline, searching forward from the previous sample's
    projection only (within a few sample steps), so a path that crosses itself (loops, a ``t``'s
    bar) is still followed in order.

    Parameters
    ----------
    path : array_like, shape (P, 2)
        The polyline (e.g. a word's points).
    samples : array_like, shape (n, 2)
        Points close to the path, in its order (e.g. the word's DMP rollout).

    Returns
    -------
    ndarray, shape (n,)
        Non-decreasing arc length (same units as ``path``) of each sample's projection.
    """
    pts = np.asarray(path, dtype=np.float64)
    smp = np.asarray(samples, dtype=np.float64)
    if len(pts) < 2:
        return np.zeros(len(smp))
    arc = arc_length(pts)
    a, b = pts[:-1], pts[1:]
    d = b - a
    length2 = np.maximum((d**2).sum(axis=1), 1e-30)
    step = np.linalg.norm(np.diff(smp, axis=0), axis=1) if len(smp) > 1 else np.zeros(1)
    # a sample moves at most its own step along the path (plus slack for the DMP's error)
    reach = 4.0 * (float(step.max()) if len(step) else 0.0) + 0.05 * (arc[-1] / len(pts)) + 1e-9
    out = np.empty(len(smp))
    s_prev, first = 0.0, 0
    for k, point in enumerate(smp):
        last = int(np.searchsorted(arc, s_prev + reach, side="right"))
        last = min(max(last, first + 1), len(a))
        seg = slice(first, last)
        u = np.clip(((point - a[seg]) * d[seg]).sum(axis=1) / length2[seg], 0.0, 1.0)
        foot = a[seg] + u[:, None] * d[seg]
        j = int(np.argmin(((foot - point) ** 2).sum(axis=1)))
        s = arc[first + j] + u[j] * math.sqrt(length2[first + j])
        s_prev = max(s_prev, s)
        out[k] = s_prev
        first = max(first, int(np.searchsorted(arc, s_prev, side="right")) - 1)
        first = min(first, len(a) - 1)
    return out


def pen_down_samples(
    points: ArrayLike, segment: ArrayLike, kinds: Sequence[str], samples: ArrayLike
) -> NDArray[np.bool_]:
    """Which samples of a motion along a word are pen-down (not pen-up travel between words).

    Parameters
    ----------
    points : array_like, shape (P, 2)
        The word's points (:class:`~prg.pipeline.word.WordTrajectory` ``points``).
    segment : array_like of int, shape (P,)
        Segment id per point.
    kinds : sequence of str
        Kind per segment; ``"space"`` segments are pen-up.
    samples : array_like, shape (n, 2)
        The motion (e.g. the DMP rollout), in the word's order.

    Returns
    -------
    ndarray of bool, shape (n,)
        False for samples strictly inside a pen-up travel, i.e. past the last point of the letter
        before it and before the first point of the letter after it (by arc length).
    """
    pts = np.asarray(points, dtype=np.float64)
    seg = np.asarray(segment)
    down = np.ones(len(samples), dtype=bool)
    spaces = [k for k, kind in enumerate(kinds) if kind == "space"]
    if not spaces:
        return down
    arc = arc_length(pts)
    s = arc_progress(pts, samples)
    for k in spaces:
        inside = np.flatnonzero(seg == k)
        before = inside[0] - 1 if inside[0] > 0 else inside[0]
        after = inside[-1] + 1 if inside[-1] + 1 < len(pts) else inside[-1]
        down &= ~((s > arc[before]) & (s < arc[after]))
    return down
