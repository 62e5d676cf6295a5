"""A hand's timing (prg.pipeline.timing.human_samples) and the measures of a pen's motion
(prg.evaluation.kinematics), on paths whose answer is known."""

from __future__ import annotations

import numpy as np
import pytest

from prg.evaluation.kinematics import (
    controls,
    kinematics,
    lognormal_snr,
    peaks_per_s,
    power_law,
    sparc,
    speed_cv,
)
from prg.pipeline.timing import human_samples, rest_to_rest_samples
from tests.helpers.kinematics import DT, _ellipse


def _harmonic(turns=4, a=2.0, b=1.0):
    t = np.arange(0.0, turns, DT)
    return np.column_stack([a * np.cos(2 * np.pi * t), b * np.sin(2 * np.pi * t)])


def test_harmonic_motion_has_the_one_third_power_law_and_constant_speed_none():
    assert power_law(_harmonic(), DT)["beta"] == pytest.approx(1 / 3, abs=0.02)
    steady, _ = rest_to_rest_samples(_ellipse(), 2.0, 0.0, 1 / DT)
    assert abs(power_law(steady, DT)["beta"]) < 0.05
    assert speed_cv(steady, DT) < 0.05


def test_the_estimator_finds_a_power_law_in_white_noise_which_is_why_it_has_a_control():
    noise = controls(_ellipse(n=1000), DT)["white noise"]
    assert 0.15 < power_law(noise, DT)["beta"] < 0.35
    constant = controls(_ellipse(n=1000), DT)["constant speed"]
    assert abs(power_law(constant, DT)["beta"]) < 0.05


def test_the_seed_varies_the_strokes_speeds_and_variation_raises_the_spread():
    path = _ellipse()
    a, _ = human_samples(path, 2.0, 0.3, 1 / DT, seed=1)
    np.testing.assert_array_equal(a, human_samples(path, 2.0, 0.3, 1 / DT, seed=1)[0])
    b, _ = human_samples(path, 2.0, 0.3, 1 / DT, seed=2)
    assert np.abs(a - b).max() > 0.01
    calm, _ = human_samples(path, 2.0, 0.3, 1 / DT, variation=0.0)
    lively, _ = human_samples(path, 2.0, 0.3, 1 / DT, variation=0.5, seed=1)
    assert speed_cv(lively, DT) > speed_cv(calm, DT)


def test_smoothness_and_peaks_tell_one_stroke_from_a_tremor():
    t = np.arange(0, 1, DT)
    stroke = np.column_stack([t**3 * (10 - 15 * t + 6 * t**2), 0 * t])  # minimum jerk
    # a slow tremor: the 0.3 s derivative window (prg.pipeline.timing.WINDOW_S) passes 3 Hz
    tremor = stroke + 0.05 * np.column_stack([0 * t, np.sin(2 * np.pi * 3 * t)])
    assert sparc(stroke, DT) > sparc(tremor, DT)
    u = np.arange(0, 1, 2 * DT)  # the same distance in two strokes, with a stop between
    half = 0.5 * (u**3 * (10 - 15 * u + 6 * u**2))
    two = np.column_stack([np.concatenate([half, 0.5 + half]), 0 * t])
    assert peaks_per_s(stroke, DT) == pytest.approx(1 / (1 - DT))
    assert peaks_per_s(two, DT) == pytest.approx(2 / (1 - DT))


def test_a_sum_of_lognormal_strokes_is_fitted_above_20_db_and_noise_is_not():
    from prg.data.sigma_lognormal import trajectory

    t = np.arange(0.0, 1.5, DT)
    params = np.array(
        [[2.0, 0.0, -1.2, 0.3, 0.2, 1.2], [1.5, 0.4, -1.0, 0.25, 1.5, 3.0]], dtype=np.float64
    )
    path = trajectory(params, t)
    assert lognormal_snr(path, DT) >= 20.0
    noise = controls(path, DT)["white noise"]
    assert lognormal_snr(noise, DT) < 10.0


def test_the_whole_report_of_a_path_is_finite():
    row = kinematics(_harmonic(turns=2), DT)
    assert set(row) == {"beta", "r2", "speed_cv", "peaks_per_s", "sparc", "lognormal_snr_db"}
    assert all(np.isfinite(v) for v in row.values())
