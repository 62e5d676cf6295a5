"""Tests of ``prg.pipeline.dmp.resample`` (moved from the suite on: discrete DMP
(prg.pipeline.dmp): reproduction, generalisation, exactness of the rollout, fit)."""

from __future__ import annotations

import numpy as np
import pytest

from prg.errors import UsageError
from prg.pipeline.dmp import (
    fit_dmp,
    rollout,
    uniform_in_time,
)
from tests.helpers.dmp import rmse

# ----------------------------------------------------------------------------- irregular times


def test_uniform_in_time_resamples_an_irregular_demonstration_for_the_fit():
    rng = np.random.default_rng(3)
    times = np.sort(rng.uniform(0.0, 2.0, 400))
    times = np.concatenate([[0.0], times, [2.0]])
    times[50] = times[49]  # two events in the same millisecond

    def path(t):
        return np.column_stack([4.0 * t + 0.6 * np.sin(3 * np.pi * t), 1.0 - np.cos(3 * np.pi * t)])

    uniform, duration = uniform_in_time(path(times), times, n_samples=500)
    assert duration == 2.0 and uniform.shape == (500, 2)
    assert rmse(uniform, path(np.linspace(0.0, 2.0, 500))) < 1e-3
    out = rollout(fit_dmp(uniform, tau=duration, n_basis=100, velocities="demonstrated"))
    assert rmse(out, path(np.linspace(0.0, 2.0, 500))) < 2e-3


@pytest.mark.parametrize(
    ("times", "message"),
    [
        ([0.0, 2.0, 1.0, 3.0], "times: expected non-decreasing values"),
        ([0.0, 0.0, 1.0, 1.0], "times: expected at least 3 distinct times"),
        ([0.0, 1.0, 2.0], r"times: expected shape \(4,\) like points"),
    ],
)
def test_uniform_in_time_refuses_times_it_cannot_resample(times, message):
    with pytest.raises(UsageError, match=message):
        uniform_in_time(np.zeros((4, 2)), times)


@pytest.mark.parametrize(
    ("times", "n_samples", "message"),
    [
        ([0.0, np.nan, 1.0, 2.0], None, "times: expected finite values"),
        ([[0.0, 1.0, 2.0, 3.0]], None, "times: expected a 1-D array"),
        ([0.0, 1.0, 2.0, 3.0], 2, "n_samples: expected an integer >= 3, got 2"),
        ([0.0, 1.0, 2.0, 3.0], 2.5, "n_samples: expected an integer >= 3"),
    ],
)
def test_uniform_in_time_names_the_argument_it_refuses(times, n_samples, message):
    with pytest.raises(UsageError, match=message):
        uniform_in_time(np.zeros((4, 2)), times, n_samples=n_samples)


def test_uniform_in_time_keeps_the_count_the_ends_and_the_span_of_a_late_start():
    """Without ``n_samples`` as many samples as given; the ends are the first and last samples
    (time-averaged where times repeat); the duration is last minus first time, also for times
    that do not start at 0; three distinct times and three samples are enough."""
    times = np.array([5.0, 5.5, 6.25, 6.25, 7.0])
    points = np.array([[0.0, 0.0], [1.0, 2.0], [2.0, 1.0], [2.5, 1.5], [3.0, 0.5]])
    uniform, duration = uniform_in_time(points, times)
    assert uniform.shape == (5, 2) and duration == 2.0
    np.testing.assert_array_equal(uniform[0], points[0])
    np.testing.assert_array_equal(uniform[-1], points[-1])
    three, span = uniform_in_time(points[:3], times[:3], n_samples=3)
    assert three.shape == (3, 2) and span == 1.25
    np.testing.assert_array_equal(three[[0, -1]], points[[0, 2]])
    last_repeated, _ = uniform_in_time(points[:4], times[:4], n_samples=3)
    np.testing.assert_array_equal(last_repeated[-1], points[2:4].mean(0))
