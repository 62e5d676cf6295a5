"""Timing: a word's path resampled uniformly in time, starting and ending at rest.

A hand does not move at constant speed: it slows in curves (the speed-curvature power law) and
writes some strokes faster than others. :func:`human_samples` (the default, through
:func:`timed_body`) times the word that way; :func:`rest_to_rest_samples` is the paper's
constant speed between ramps (``generate.timing=constant``).

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

import functools
import math
from typing import TYPE_CHECKING

import numpy as np
import scipy.fft
from scipy.ndimage import convolve1d, fourier_gaussian, gaussian_filter1d
from scipy.signal import savgol_coeffs

from prg.errors import UsageError

if TYPE_CHECKING:
    from prg.pipeline.word import WordTrajectory

MIN_STROKE_S = 0.2
MAX_DMP_SAMPLES = 20_000  # 200 s of writing at 100 samples/s: about 1 GB and 25 s to fit


def _cumulative_length(points: np.ndarray) -> np.ndarray:
    """Arc length at each point of a path (P, 2), from 0."""
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(steps)])


def _arc(points: np.ndarray) -> np.ndarray:
    """:func:`_cumulative_length` of a word's path; one error when it has no length."""
    arc = _cumulative_length(points)
    if arc[-1] <= 0:
        raise UsageError("the word trajectory has zero length: nothing to write")
    return arc


def _along(points: np.ndarray, arc: np.ndarray, s: np.ndarray) -> np.ndarray:
    """The points of a path (P, 2) at arc lengths ``s``, linearly between its points."""
    return np.column_stack([np.interp(s, arc, points[:, 0]), np.interp(s, arc, points[:, 1])])


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
    arc = _arc(points)
    length = arc[-1]
    # a profile of plateau speed v with ramps r: length = v (T - r), mean speed = length / T
    duration = length / speed_cm_s
    ramp = min(ramp_s, duration / 2)
    plateau = length / (duration - ramp)
    n = _sample_count(length, speed_cm_s, samples_per_s)
    t = np.linspace(0.0, duration, n)
    s = plateau * _ramped_distance(t, duration, ramp)
    s = np.clip(s * length / s[-1], 0.0, length)
    return _along(points, arc, s), duration


#: The speed-curvature power law's exponent of human drawing and cursive writing (Lacquaniti,
#: Terzuolo & Viviani 1983): the pen slows in curves, v = K kappa^(-1/3).
POWER_LAW_BETA = 1.0 / 3.0
#: Curvature (1/cm) outside this range is clipped: a straight run does not race, a cusp does
#: not stop the pen.
CURVATURE_RANGE = (0.05, 20.0)
#: The Savitzky-Golay window (cubic, seconds) of the derivatives that measure a path's speed and
#: curvature. At 0.3 s the speed-curvature estimator of :mod:`prg.evaluation.kinematics` gives
#: the reference values quoted for it: beta median 0.14 on the LASA demonstrations, about 0.25
#: on white noise (0.05 s: -0.01 and 0.23); shorter windows see the decoded letters' polyline
#: corners instead of the movement's curvature.
WINDOW_S = 0.3
CURVATURE_DT = 0.01  # s: the clock's samples when the curvature is measured
#: The speed profile is smoothed over this much path (cm), as a hand does not change speed in
#: an instant: with 0.05 the Panda's joint 4 needed its timing slowed 1.004x on the Hershey
#: word "h i" (acceleration limit), with 0.1 not; the power law's beta measured on 10 demo words
#: went from 0.24 to 0.22 (0.2: 0.19).
SPEED_SMOOTH_CM = 0.1
#: Curvature (1/cm, the path's own at 0.2 mm) above which a point is a cusp where the pen turns
#: back (the foot of a Hershey h): the pen slows there whatever the movement-scale curvature
#: says, or the arm's joints accelerate past their limits (Panda joint 4 on "h i": 1.07x).
CUSP_KAPPA = 40.0
#: The pen's largest speed-up or slow-down along its path (cm/s^2).
MAX_PEN_ACCEL = 30.0
POWER_LAW_PASSES = 3  # the timing and the curvature it measures agree after a few passes


def speed_and_curvature(
    xy: np.ndarray, dt: float, window_s: float = WINDOW_S
) -> tuple[np.ndarray, np.ndarray]:
    """Speed and curvature of a path sampled every ``dt`` seconds (Savitzky-Golay derivatives,
    cubic, ``window_s`` seconds, at least 5 samples), each shape (n,)."""
    xy = np.asarray(xy, dtype=np.float64)
    if len(xy) < 5:
        return np.zeros(len(xy)), np.zeros(len(xy))
    window = min(max(5, round(window_s / dt) | 1), len(xy) - (1 - len(xy) % 2))
    vel = savgol_derivative(xy, window, 1, dt)
    acc = savgol_derivative(xy, window, 2, dt)
    speed = np.linalg.norm(vel, axis=1)
    cross = np.abs(vel[:, 0] * acc[:, 1] - vel[:, 1] * acc[:, 0])
    return speed, cross / np.maximum(speed, 1e-12) ** 3


def savgol_derivative(xy: np.ndarray, window: int, deriv: int, delta: float) -> np.ndarray:
    """``scipy.signal.savgol_filter(xy, window, 3, deriv, delta=delta, axis=0)`` (its default
    ``mode="interp"``) on a path ``xy`` (n, d) with ``window <= n`` odd, from operators built
    once per window (:func:`_savgol_operators`): savgol_filter rebuilds its kernel and fits the
    two edges with ``polyfit`` on every call, which was most of a word's timing.

    >>> from scipy.signal import savgol_filter
    >>> xy = np.random.default_rng(0).normal(size=(40, 2)).cumsum(axis=0)
    >>> ours = savgol_derivative(xy, 11, 1, 0.01)
    >>> bool(np.allclose(ours, savgol_filter(xy, 11, 3, deriv=1, delta=0.01, axis=0)))
    True
    """
    kernel, head, tail = _savgol_operators(window, deriv, delta)
    out = convolve1d(xy, kernel, axis=0, mode="constant")
    half = window // 2
    out[:half] = head @ xy[:window]
    out[len(xy) - half :] = tail @ xy[-window:]
    return out


@functools.lru_cache(maxsize=32)
def _savgol_operators(window: int, deriv: int, delta: float) -> tuple[np.ndarray, ...]:
    """The cubic Savitzky-Golay derivative of one window: the interior kernel (for
    ``convolve1d``) and the (window // 2, window) matrices that evaluate the cubic fitted to
    the first and the last ``window`` samples at the first and the last ``window // 2``."""
    half = window // 2

    def at(positions) -> np.ndarray:
        return np.stack(
            [savgol_coeffs(window, 3, deriv, delta, pos=p, use="dot") for p in positions]
        )

    return savgol_coeffs(window, 3, deriv, delta), at(range(half)), at(range(window - half, window))


def human_samples(
    points: np.ndarray,
    speed_cm_s: float,
    ramp_s: float,
    samples_per_s: float,
    seed: int = 0,
    variation: float = 0.25,
    beta: float = POWER_LAW_BETA,
) -> tuple[np.ndarray, float]:
    """Resample a path uniformly in time under a hand's speed profile.

    The speed follows the speed-curvature power law ``v = K kappa^(-beta)`` (the pen slows in
    curves and speeds up on straighter parts), the curvature measured on the path as the timing
    itself draws it, at the time scale of a movement (:func:`speed_and_curvature`, a few passes
    until the two agree) and clipped to :data:`CURVATURE_RANGE`;
    it is modulated stroke by stroke by a smooth random factor ``exp(variation * g(s))``
    (``g`` Gaussian noise smoothed over 0.8 cm of path, unit std, seeded): people write some
    strokes faster than others. The pen starts and ends at rest (the hand's clock run through
    the half-cosine ramps of ``ramp_s`` seconds of :func:`rest_to_rest_samples`), and the whole
    is scaled so that the duration is the constant-speed one, ``length / speed_cm_s``: the word
    takes no longer than at the paper's constant speed.

    Parameters
    ----------
    points : ndarray, shape (P, 2)
        The path (centimetres).
    speed_cm_s : float
        Mean speed over the whole path (> 0).
    ramp_s : float
        Duration of the start and stop envelopes (>= 0).
    samples_per_s : float
        Output samples per second (> 0).
    seed : int
        Seeds the stroke-to-stroke variation.
    variation : float
        Its strength (0: the power law alone).
    beta : float
        The power law's exponent.

    Returns
    -------
    samples : ndarray, shape (n, 2)
    duration : float
        Seconds: ``length / speed_cm_s``.
    """
    points = np.asarray(points, dtype=np.float64)
    arc = _arc(points)
    length = arc[-1]
    duration = length / speed_cm_s
    n = _sample_count(length, speed_cm_s, samples_per_s)
    ds = 0.005  # cm: the path resampled finely, equal steps
    fine = max(int(np.ceil(length / ds)) + 1, 8)
    s = np.linspace(0.0, length, fine)
    ds = s[1] - s[0]
    factor = np.ones(fine)
    if variation > 0:
        sigma = 0.8 / ds
        # periodic noise smoothed in Fourier space, on a length the FFT is fast for, cut to
        # the path (in direct form the 6.4 cm kernel on a 0.05 mm grid cost 1 ms a word)
        period = scipy.fft.next_fast_len(fine, real=True)
        noise = scipy.fft.rfft(np.random.default_rng(seed).normal(size=period))
        g = scipy.fft.irfft(fourier_gaussian(noise, sigma, n=period), period)[:fine]
        # unit std for white noise so smoothed (a constant, not this path's own std: a path
        # shorter than the smoothing keeps a near-constant factor, which the duration cancels)
        factor = np.exp(variation * g * math.sqrt(2.0 * math.sqrt(math.pi) * sigma))
    # the path's own curvature at 0.2 mm: a cusp (the foot of an h, where the pen turns back)
    # must slow the pen, though the movement-scale curvature below smears it out
    fine_xy = _along(points, arc, s)
    heading = np.unwrap(np.arctan2(*np.gradient(fine_xy, axis=0)[:, ::-1].T))
    cusp = np.abs(gaussian_filter1d(np.gradient(heading, ds), 0.02 / ds, mode="nearest"))
    own = s / speed_cm_s  # the hand's own clock along the path, first at constant speed
    for _ in range(POWER_LAW_PASSES):
        # the curvature of the path as this clock draws it, at the scale of a movement (the
        # derivatives' window in time): where a hand's power law holds, not at the jitter of
        # the decoded points
        grid = np.arange(0.0, own[-1], CURVATURE_DT)
        at = np.interp(grid, own, s)
        xy = _along(points, arc, at)
        _, kappa = speed_and_curvature(xy, CURVATURE_DT)
        kappa = np.interp(s, at, kappa)
        kappa = np.where(cusp > CUSP_KAPPA, np.maximum(kappa, cusp), kappa)
        speed = np.clip(kappa, *CURVATURE_RANGE) ** (-beta) * factor
        speed = np.exp(gaussian_filter1d(np.log(speed), SPEED_SMOOTH_CM / ds, mode="nearest"))
        own = _clock(speed, ds, duration)
    for _ in range(2):  # limit the pen's speed-up and slow-down (cm/s^2), then keep the duration
        speed = _limit_acceleration(ds / np.maximum(np.diff(own), 1e-12), ds, MAX_PEN_ACCEL)
        speed = np.concatenate([speed, speed[-1:]])
        own = _clock(speed, ds, duration)
    # rest at both ends: the hand's clock is run through the same half-cosine ramps in time as
    # the constant profile's (rest_to_rest_samples), so the pen starts and stops smoothly
    ramp = min(ramp_s, duration / 2)
    clock = _ramped_distance(np.linspace(0.0, duration, n), duration, ramp)
    s_at = np.interp(clock * own[-1] / clock[-1], own, s)
    return _along(points, arc, s_at), duration


def _clock(speed: np.ndarray, ds: float, duration: float) -> np.ndarray:
    """Times at which a pen moving at ``speed`` (per step ``ds``) reaches each step, scaled to
    ``duration``."""
    own = np.concatenate([[0.0], np.cumsum(ds / (0.5 * (speed[1:] + speed[:-1])))])
    return own * (duration / own[-1])


def _limit_acceleration(speed: np.ndarray, ds: float, accel: float) -> np.ndarray:
    """``speed`` (cm/s, per path step ``ds``) lowered where it would change faster than
    ``accel`` (cm/s^2): the forward and backward passes of v dv/ds <= accel (a time-optimal
    planner's, here only to cap what the power law asks near cusps).

    Each pass is a running minimum: in squares, ``v_i^2 <= v_(i-1)^2 + 2 accel ds`` for every
    step means ``v_i^2 - 2 accel ds i`` never rises along the pass (the loop it replaces was
    most of a word's write time)."""
    steps = 2.0 * accel * ds * np.arange(len(speed))
    squared = np.asarray(speed, dtype=np.float64) ** 2
    squared = np.minimum.accumulate(squared - steps) + steps  # speeding up
    squared = np.minimum.accumulate((squared + steps)[::-1])[::-1] - steps  # slowing down
    return np.sqrt(np.maximum(squared, 0.0))


def _sample_count(length: float, speed_cm_s: float, samples_per_s: float) -> int:
    duration = length / speed_cm_s
    n = max(3, int(np.ceil(duration * samples_per_s)) + 1)
    if n > MAX_DMP_SAMPLES:  # the DMP fit's time and memory grow with n squared
        raise UsageError(
            f"the word is {length:.1f} cm long: at generate.speed_cm_s={speed_cm_s:g} and "
            f"generate.samples_per_s={samples_per_s:g} its DMP would take {n:,} samples "
            f"({duration:.0f} s); accepted are at most {MAX_DMP_SAMPLES:,}: write faster or less"
        )
    return n


def timed_body(points: np.ndarray, settings) -> tuple[np.ndarray, float]:
    """The word's body resampled uniformly in time as ``settings``
    (:class:`~prg.pipeline.compose.GenerateSettings`) times it: :func:`human_samples` (the
    default, ``timing="human"``, seeded by ``settings.seed``) or :func:`rest_to_rest_samples`
    (the paper's constant speed, ``timing="constant"``). The DMP is fitted to these samples."""
    if settings.timing == "constant":
        return rest_to_rest_samples(
            points, settings.speed_cm_s, settings.ramp_s, settings.samples_per_s
        )
    return human_samples(
        points,
        settings.speed_cm_s,
        settings.ramp_s,
        settings.samples_per_s,
        seed=settings.seed,
        variation=settings.speed_variation,
    )


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
    arc = _cumulative_length(points)
    n = max(2, int(np.ceil(duration / dt)) + 1)
    s = min_jerk(n) * arc[-1]
    return _along(points, arc, s)


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
