"""Helpers shared by the tests that were split out of tests/test_dmp.py."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from prg.pipeline.dmp import (
    DMP,
    design_matrix,
    fit_dmp,
)


def word_like(n: int = 1000, loops: int = 12, width: float = 20.0, height: float = 4.0):
    """A cursive-like curve in cm: ``loops`` loops of varying height, ``width`` x ``height``.

    Sampled uniformly in time with a minimum-jerk time course, so the pen starts and ends at rest.
    """
    t = np.linspace(0.0, 1.0, n)
    s = 10 * t**3 - 15 * t**4 + 6 * t**5
    angle = 2 * np.pi * loops * s
    amplitude = 0.55 + 0.45 * np.sin(2 * np.pi * 2.3 * s + 0.7) ** 2  # ascenders and x-height
    x = s - 0.045 * np.sin(angle)
    y = amplitude * (1 - np.cos(angle)) + 0.15 * np.sin(np.pi * s)
    x = (x - x.min()) / np.ptp(x) * width
    y = (y - y.min()) / np.ptp(y) * height
    return np.column_stack([x, y])


def rmse(a: np.ndarray, b: np.ndarray) -> float:
    """Root mean squared Euclidean distance between corresponding points."""
    return float(np.sqrt(np.mean(np.sum((a - b) ** 2, axis=1))))


def rk4_reference(dmp: DMP, n_samples: int, y0=None, goal=None, tau=None, substeps: int = 10):
    """Per-step RK4 integration of the DMP's ODE, written from the formulation, not the code.

    ``y' = v / tau``, ``v' = (K (g_m - y) + D (tau g' - v) - K (g - y0) x + K f(x)) / tau`` with
    the moving goal ``g_m = g - g' (tau - t)``, ``x = exp(-alpha_x t / tau)`` and ``f =
    design_matrix(x) @ weights``, from ``(y0, tau y0')``, ``substeps`` RK4 steps between output
    samples (``y0'``, ``g'``: the DMP's start and goal velocities).
    """
    y0 = dmp.y0 if y0 is None else np.asarray(y0, float)
    goal = dmp.goal if goal is None else np.asarray(goal, float)
    tau = dmp.tau if tau is None else tau
    goal_v = dmp.goal_velocity
    k_, d_ = dmp.stiffness, dmp.damping
    steps = (n_samples - 1) * substeps
    h = tau / steps
    half_times = np.arange(2 * steps + 1) * (h / 2)  # every RK4 stage time
    x_half = np.exp(-dmp.alpha_x * half_times / tau)
    f_half = design_matrix(x_half, dmp.centres, dmp.widths) @ dmp.weights

    def acceleration(j: int, y: np.ndarray, v: np.ndarray) -> np.ndarray:
        moving_goal = goal - goal_v * (tau - half_times[j])
        return (
            k_ * (moving_goal - y)
            + d_ * (tau * goal_v - v)
            - k_ * (goal - y0) * x_half[j]
            + k_ * f_half[j]
        ) / tau

    y, v = y0.copy(), tau * dmp.start_velocity
    out = [y.copy()]
    for i in range(steps):
        j = 2 * i
        k1y, k1v = v / tau, acceleration(j, y, v)
        k2y, k2v = (v + h / 2 * k1v) / tau, acceleration(j + 1, y + h / 2 * k1y, v + h / 2 * k1v)
        k3y, k3v = (v + h / 2 * k2v) / tau, acceleration(j + 1, y + h / 2 * k2y, v + h / 2 * k2v)
        k4y, k4v = (v + h * k3v) / tau, acceleration(j + 2, y + h * k3y, v + h * k3v)
        y = y + h / 6 * (k1y + 2 * k2y + 2 * k3y + k4y)
        v = v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        if (i + 1) % substeps == 0:
            out.append(y.copy())
    return np.array(out)


@pytest.fixture(scope="module")
def word():
    points = word_like()
    assert points.shape == (1000, 2)
    assert_allclose(np.ptp(points, axis=0), [20.0, 4.0])
    return points


@pytest.fixture(scope="module")
def word_dmp(word):
    return fit_dmp(word, tau=3.0)


# ----------------------------------------------------------------------------- moving ends


def moving_curve(n: int = 1000, tau: float = 2.0) -> np.ndarray:
    """A loopy 2-D curve (cm) that is already moving at its first sample and still at its last:
    constant drift plus loops, uniform in time over ``tau``."""
    t = np.linspace(0.0, tau, n)
    angle = 2 * np.pi * 3 * t / tau
    return np.column_stack([4.0 * t + 0.6 * np.sin(angle), 1.0 - np.cos(angle) + 0.5 * t])
