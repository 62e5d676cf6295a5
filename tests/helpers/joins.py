"""Helpers shared by the tests that were split out of tests/test_joins.py."""

from __future__ import annotations

import numpy as np


def _arc(centre, radius, start_deg, end_deg, n=60):
    a = np.radians(np.linspace(start_deg, end_deg, n))
    return np.column_stack([centre[0] + radius[0] * np.cos(a), centre[1] + radius[1] * np.sin(a)])
