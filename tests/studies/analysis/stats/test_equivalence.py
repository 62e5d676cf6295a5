"""Tests of ``studies.analysis.stats.equivalence`` (moved from the suite on: studies.analysis
statistics: each function against the scipy/statsmodels call it names, and the paper's numbers
(shared/reference/studies.md) reproduced from the paper's summaries)."""

from __future__ import annotations

import pytest
from statsmodels.stats.proportion import binom_tost, proportion_confint

from studies.analysis import stats as S
from studies.analysis.paper import (
    paper_turing_frame,
)
from tests.helpers.study_analysis import binary_frame, close, fields


def test_binomial_tost_matches_binom_tost_and_names_the_null_not_rejected():
    row = S.binomial_tost(binary_frame(211, 500), "y", 0.2, 0.057).iloc[0]
    p, p_low, p_upp = binom_tost(211, 500, 0.143, 0.257)
    assert p_low < 1e-50  # the lower null is rejected overwhelmingly: compared relatively
    close(fields(row, "p_value", "p_lower", "p_upper"), [p, p_low, p_upp], 1e-12)
    close(fields(row, "ci_low", "ci_high"), proportion_confint(211, 500, 0.1, method="beta"), 1e-12)
    assert row.estimate == 211 / 500 and row.statistic == 211 and row.ci_level == 0.9
    assert not row.reject
    assert "'rate >= 0.257'" in row.conclusion and "'rate <= 0.143'" not in row.conclusion
    assert "86 <= k <= 112" in row.method


def test_binomial_tost_shows_equivalence_at_chance_with_enough_trials():
    row = S.binomial_tost(binary_frame(100, 500), "y", 0.2, 0.057).iloc[0]
    assert row.reject and row.conclusion.startswith("equivalent")
    assert 0.143 < row.ci_low < row.ci_high < 0.257 and row.ci_level == pytest.approx(0.9)


def test_margin_warnings_flag_data_derived_and_look_alike_margins_only():
    df = paper_turing_frame()
    cands = S.margin_candidates(df, "chose_robot")
    assert cands["the SD across words"] == pytest.approx(0.0569, abs=1e-4)
    assert "derived from the data" in S.margin_warnings(0.057, "data", cands)[0]
    looks = S.margin_warnings(0.057, "unstated", cands)
    assert len(looks) == 1 and "the SD across words" in looks[0]
    assert S.margin_warnings(0.057, "preregistered", cands) == []
    assert S.margin_warnings(0.10, "unstated", cands) == []
    assert "no equivalence margin was configured" in S.margin_warnings(0.05, "default", cands)[0]
