"""Helpers shared by the tests that were split out of tests/test_study_analysis_simulated.py."""

from __future__ import annotations

from studies.analysis.participants import (
    simulate_turing,
)
from studies.analysis.validate import analysis_rows, check_responses


def turing_rows(**kw):
    table, truth = simulate_turing(**kw)
    return analysis_rows(check_responses(table).frame)[0], truth
