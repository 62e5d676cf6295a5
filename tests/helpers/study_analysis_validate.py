"""Helpers shared by the tests that were split out of tests/test_study_analysis_validate.py."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from studies.analysis.participants import simulate_readability, simulate_turing

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def turing_table() -> pd.DataFrame:
    return simulate_turing(6, 0.3, seed=1, inattentive=1)[0].astype(str)


@pytest.fixture(scope="module")
def readability_table() -> pd.DataFrame:
    return simulate_readability(6, 0.8, seed=1)[0].astype(str)
