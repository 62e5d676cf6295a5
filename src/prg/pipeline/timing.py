"""Timing: a word's path resampled uniformly in time, starting and ending at rest.

A DMP starts and ends at rest, so the word is not fitted at constant pen speed (its first
samples would need an initial velocity the DMP does not have: an error of about 3 % of the
path length near the start). :func:`rest_to_rest_samples` resamples the path uniformly in time
under a speed profile that rises and falls with half-cosine ramps of ``ramp_s`` seconds and is
constant in between; the mean speed over the word stays ``speed_cm_s``.

The delayed strokes (:mod:`prg.pipeline.marks`) and the pen-up travels to them are not part of
the DMP: each is a short straight stroke (a bar, a travel) or a tiny circle (a dot) that a DMP
would only smooth away. :func:`stroke_samples` times each along its own path with the
minimum-jerk rest-to-rest profile (:func:`min_jerk`), in :func:`stroke_duration` seconds: the
word's mean speed, but at least :data:`MIN_STROKE_S`, so the pen settles on a dot instead of
flicking it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from prg.errors import UsageError

if TYPE_CHECKING:
    from prg.pipeline.word import WordTrajectory

MIN_STROKE_S = 0.2
MAX_DMP_SAMPLES = 20_000  # 200 s of writing at 100 samples/s: about 1 GB and 25 s to fit


def rest_to_rest_samples(
    points: np.ndarray, speed_cm_s: float, ramp_s: float, samples_per_s: float
) -> tuple[np.ndarray, float]:
    """Resample a path uniformly in time under a rest-to-rest speed profile.

    Parameters
    ----------
    points : ndarray, shape (P, 2)
        The path (centimetres).
    speed_cm_s : float
        Mean speed over the whole path (> 0).
    ramp_s : float
        Duration of the half-cosine speed-up and slow-down (>= 0).
    samples_per_s : float
        Output samples per second (> 0).

    Returns
    -------
    samples : ndarray, shape (n, 2)
    duration : float
        Seconds.
    """
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(steps)])
    length = arc[-1]
    if length <= 0:
        raise UsageError("the word trajectory has zero length: nothing to write")
    # a profile of plateau speed v with ramps r: length = v (T - r), mean speed = length / T
    duration = length / speed_cm_s
    ramp = min(ramp_s, duration / 2)
    plateau = length / (duration - ramp)
    n = max(3, int(np.ceil(duration * samples_per_s)) + 1)
    if n > MAX_DMP_SAMPLES:  # the DMP fit's time and memory grow with n squared
        raise UsageError(
            f"the word is {length:.1f} cm long: at generate.speed_cm_s={speed_cm_s:g} and "
            f"generate.samples_per_s={samples_per_s:g} its DMP would take {n:,} samples "
            f"({duration:.0f} s); accepted are at most {MAX_DMP_SAMPLES:,}: write faster or less"
        )
    t = np.linspace(0.0, duration, n)
    s = plateau * _ramped_distance(t, duration, ramp)
    s = np.clip(s * length / s[-1], 0.0, length)
    x = np.interp(s, arc, points[:, 0])
    y = np.interp(s, arc, points[:, 1])
    return np.stack([x, y], axis=1), duration


def _ramped_distance(t: np.ndarray, duration: float, ramp: float) -> np.ndarray:
    """Distance travelled at unit plateau speed with half-cosine ramps (closed form)."""
    if ramp == 0:
        return t.copy()

    def up(u):  # integral of (1 - cos(pi u / ramp)) / 2 from 0 to u
        return 0.5 * (u - ramp / np.pi * np.sin(np.pi * u / ramp))

    total = duration - ramp
    return np.where(
        t < ramp,
        up(t),
        np.where(t > duration - ramp, total - up(duration - t), up(ramp) + (t - ramp)),
    )


def min_jerk(n: int) -> np.ndarray:
    """The minimum-jerk rest-to-rest profile ``10u^3 - 15u^4 + 6u^5`` on ``n`` samples of [0, 1]."""
    u = np.linspace(0.0, 1.0, n)
    return u**3 * (10.0 - 15.0 * u + 6.0 * u**2)


def stroke_duration(points: np.ndarray, speed_cm_s: float) -> float:
    """Seconds for a delayed stroke or travel along ``points``: length / speed, at least
    :data:`MIN_STROKE_S`."""
    length = float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())
    return max(length / speed_cm_s, MIN_STROKE_S)


def stroke_samples(points: np.ndarray, duration: float, dt: float) -> np.ndarray:
    """``points`` (m, 2) followed from rest to rest in ``duration`` seconds under the
    minimum-jerk profile, one sample every ``dt`` seconds or a little less (both ends included),
    shape (n >= 2, 2)."""
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(steps)])
    n = max(2, int(np.ceil(duration / dt)) + 1)
    s = min_jerk(n) * arc[-1]
    return np.column_stack([np.interp(s, arc, points[:, 0]), np.interp(s, arc, points[:, 1])])


def delayed_samples(
    word: WordTrajectory, dt: float, tempo: float = 1.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The motion after the word's body: each pen-up travel and delayed stroke in turn
    (:meth:`WordTrajectory.delayed_strokes`), from rest to rest.

    Returns
    -------
    samples : ndarray, shape (n, 2)
        Centimetres; the body's last point (where the motion starts) is not repeated.
    t : ndarray, shape (n,)
        Seconds after the body's end, increasing.
    pen_down : ndarray of bool, shape (n,)
        True on the marks and at the end of each travel (where the pen goes down).
    """
    xy, t, down = [np.empty((0, 2))], [np.empty(0)], [np.empty(0, dtype=bool)]
    clock = 0.0
    for kind, path in word.delayed_strokes():
        duration = stroke_duration(path, word.speed_cm_s) * tempo
        part = stroke_samples(path, duration, dt)[1:]
        flags = np.full(len(part), kind == "mark")
        flags[-1] = True  # a travel ends where its mark begins: the pen goes down there
        xy.append(part)
        t.append(clock + np.linspace(0.0, duration, len(part) + 1)[1:])
        down.append(flags)
        clock += duration
    return np.concatenate(xy), np.concatenate(t), np.concatenate(down)
