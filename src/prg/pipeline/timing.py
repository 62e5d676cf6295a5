"""Timing: a word's path resampled uniformly in time, starting and ending at rest.

A DMP starts and ends at rest, so the word is not fitted at constant pen speed (its first
samples would need an initial velocity the DMP does not have: an error of about 3 % of the
path length near the start). :func:`rest_to_rest_samples` resamples the path uniformly in time
under a speed profile that rises and falls with half-cosine ramps of ``ramp_s`` seconds and is
constant in between; the mean speed over the word stays ``speed_cm_s``.
"""

from __future__ import annotations

import numpy as np

from prg.errors import UsageError

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
