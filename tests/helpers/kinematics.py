"""Helpers shared by the tests that were split out of tests/test_kinematics.py."""

from __future__ import annotations

import numpy as np

DT = 0.01


def _ellipse(turns=3, a=2.0, b=0.7, n=3000):
    th = np.linspace(0.0, 2 * np.pi * turns, n)
    return np.column_stack([a * np.cos(th), b * np.sin(th)])
