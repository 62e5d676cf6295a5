"""Tests of ``prg.pipeline.timing`` (moved from the suite on: generate: per-letter decoding, input
subsets per family, rest-to-rest timing, one DMP a word)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.signal import savgol_filter

from prg.evaluation.kinematics import (
    power_law,
)
from prg.pipeline.timing import (
    human_samples,
    min_jerk,
    rest_to_rest_samples,
    savgol_derivative,
    speed_and_curvature,
)
from tests.helpers.kinematics import DT, _ellipse


def test_rest_to_rest_timing_keeps_the_path_and_the_mean_speed():
    t = np.linspace(0, 4 * np.pi, 400)
    path = np.stack([t, np.sin(3 * t)], axis=1)
    length = np.linalg.norm(np.diff(path, axis=0), axis=1).sum()
    samples, duration = rest_to_rest_samples(path, speed_cm_s=2.0, ramp_s=0.3, samples_per_s=200)
    assert duration == pytest.approx(length / 2.0)
    np.testing.assert_allclose(samples[[0, -1]], path[[0, -1]], atol=1e-9)
    speed = np.linalg.norm(np.diff(samples, axis=0), axis=1) * 200
    assert speed[0] < 0.05 * speed.max() and speed[-1] < 0.05 * speed.max()  # starts, ends at rest
    # every sample lies on the path (within the chord error of its polyline)
    nearest = np.min(np.linalg.norm(samples[:, None] - path[None], axis=2), axis=1)
    assert nearest.max() < 0.05


def test_a_hand_slows_in_curves_and_takes_the_constant_speed_time():
    path = _ellipse()
    samples, duration = human_samples(path, 2.0, 0.3, 1 / DT, variation=0.0)
    steady, steady_duration = rest_to_rest_samples(path, 2.0, 0.3, 1 / DT)
    assert duration == pytest.approx(steady_duration)
    assert samples.shape == steady.shape
    np.testing.assert_allclose(samples[[0, -1]], path[[0, -1]], atol=1e-9)
    speed, kappa = speed_and_curvature(samples, DT)
    middle = slice(50, -50)  # away from the rest-to-rest ramps
    tight = kappa[middle] > np.percentile(kappa[middle], 80)
    loose = kappa[middle] < np.percentile(kappa[middle], 20)
    assert speed[middle][tight].mean() < 0.8 * speed[middle][loose].mean()
    assert 0.2 < power_law(samples, DT)["beta"] < 0.45
    assert speed[0] < 0.1 * speed.max() and speed[-1] < 0.1 * speed.max()  # from rest to rest


def test_every_sample_lies_on_the_path():
    path = _ellipse(turns=1, n=400)
    samples, _ = human_samples(path, 2.0, 0.3, 1 / DT, seed=3)
    nearest = np.min(np.linalg.norm(samples[:, None] - path[None], axis=2), axis=1)
    assert nearest.max() < 0.02


def test_a_path_shorter_than_the_smoothing_is_timed_without_overflow():
    samples, duration = human_samples(np.array([[0.0, 0.0], [0.0, 0.2]]), 2.0, 0.3, 100)
    assert np.isfinite(samples).all() and duration == pytest.approx(0.1)


def test_min_jerk_rests_at_both_ends():
    s = min_jerk(101)
    assert s[0] == 0 and s[-1] == 1 and np.all(np.diff(s) >= 0)
    v = np.diff(s)
    assert v[0] < 1e-4 and v[-1] < 1e-4


@settings(max_examples=60, deadline=None)
@given(
    log_speed=st.lists(st.floats(-3.0, 3.0), min_size=1, max_size=300),
    accel=st.floats(0.5, 500.0),
)
def test_the_pen_speeds_up_and_slows_down_no_faster_than_its_limit(log_speed, accel):
    """The cap is the largest profile under the asked one whose change per step obeys
    v dv/ds <= accel both ways: below the asked speed everywhere, within the limit between
    every two steps, and touching the asked speed wherever the limit allows it (the forward
    and backward passes written out step by step)."""
    from prg.pipeline.timing import _limit_acceleration

    ds = 0.005
    asked = np.exp(np.array(log_speed))
    capped = _limit_acceleration(asked, ds, accel)
    reach = 2.0 * accel * ds
    assert np.all(capped <= asked * (1 + 1e-9))
    assert np.all(np.abs(np.diff(capped**2)) <= reach * (1 + 1e-6) + 1e-9)
    expected = asked.copy()
    for i in range(1, len(expected)):
        expected[i] = min(expected[i], math.sqrt(expected[i - 1] ** 2 + reach))
    for i in range(len(expected) - 2, -1, -1):
        expected[i] = min(expected[i], math.sqrt(expected[i + 1] ** 2 + reach))
    np.testing.assert_allclose(capped, expected, rtol=1e-8)


@settings(max_examples=80, deadline=None)
@given(
    n=st.integers(5, 120),
    window_share=st.floats(0.0, 1.0),
    deriv=st.sampled_from([0, 1, 2, 3]),
    delta=st.floats(1e-3, 1.0),
    seed=st.integers(0, 2**16),
)
def test_savgol_derivative_is_scipys_savgol_filter(n, window_share, deriv, delta, seed):
    """The cached operators give what scipy.signal.savgol_filter gives (cubic, mode="interp"),
    interior and both edges, for any odd window from 5 to the path's length."""
    largest = n if n % 2 else n - 1
    window = 5 + 2 * round(window_share * (largest - 5) / 2)
    xy = np.random.default_rng(seed).normal(size=(n, 2)).cumsum(axis=0)
    expected = savgol_filter(xy, window, 3, deriv=deriv, delta=delta, axis=0)
    scale = np.abs(expected).max() + 1.0
    np.testing.assert_allclose(
        savgol_derivative(xy, window, deriv, delta), expected, atol=1e-9 * scale
    )


def test_the_stroke_to_stroke_variation_has_the_asked_strength_and_length():
    """On a straight line (the power law's speed is constant there) the pen's log speed varies
    with the asked standard deviation, and is correlated over the 0.8 cm of path the noise is
    smoothed over: exp(-lag^2 / (4 sigma^2)) for Gaussian-smoothed white noise."""
    line = np.column_stack([np.linspace(0.0, 200.0, 50), np.zeros(50)])
    grid = np.arange(5.0, 195.0, 0.05)
    stds, near, far = [], [], []
    for seed in range(3):
        samples, _ = human_samples(line, 2.0, 0.3, 100, seed=seed, variation=0.25)
        speed = np.linalg.norm(np.diff(samples, axis=0), axis=1) * 100
        log_speed = np.log(np.interp(grid, samples[1:, 0], speed))
        log_speed -= log_speed.mean()
        stds.append(log_speed.std())

        near.append(_autocorrelation(log_speed, round(0.8 / 0.05)))
        far.append(_autocorrelation(log_speed, round(3.2 / 0.05)))
    assert np.mean(stds) == pytest.approx(0.25, rel=0.15)
    assert np.mean(near) == pytest.approx(math.exp(-0.25), abs=0.1)
    assert abs(np.mean(far)) < 0.2


def _autocorrelation(centred: np.ndarray, lag: int) -> float:
    return float((centred[:-lag] * centred[lag:]).mean() / centred.var())
