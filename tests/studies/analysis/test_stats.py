"""Tests of ``studies.analysis.stats`` (moved from the suite on: studies.analysis statistics: each
function against the scipy/statsmodels call it names, and the paper's numbers
(shared/reference/studies.md) reproduced from the paper's summaries)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from studies.analysis import stats as S
from studies.analysis.analyze import analyze_table
from studies.analysis.config import AnalysisSettings
from studies.analysis.paper import (
    paper_readability_frame,
    paper_turing_frame,
)
from studies.analysis.participants import (
    simulate_turing,
)
from studies.analysis.report import build_report
from studies.analysis.stats import TEST_COLUMNS
from tests.helpers.study_analysis_report import both_studies  # noqa: F401 (fixtures)
from tests.helpers.study_analysis_simulated import turing_rows


def test_the_papers_conclusions_follow_from_its_summary_numbers():
    t1, t2 = paper_turing_frame(), paper_readability_frame()
    assert S.binomial_test(t1, "chose_robot", 0.2).iloc[0].reject  # "far from a random guess"
    assert (
        not S.binomial_tost(t1, "chose_robot", 0.2, 0.057).iloc[0].reject
    )  # equivalence not shown
    assert (
        S.one_sample_ttest(t1, "confidence", 3, "greater").iloc[0].reject
    )  # "rejected below neutral"
    assert not S.group_ttest(t2, "correct").iloc[0].reject  # two-sided t-test "not rejected"


def test_tests_csv_is_tidy_one_row_per_test_for_both_approaches(both_studies):
    tests = pd.read_csv(both_studies[1] / "tests.csv")
    assert list(tests.columns) == ["study", "approach", "hypothesis", *TEST_COLUMNS]
    assert set(tests.approach) == {"paper-faithful", "recommended"}
    assert set(tests.study) == {"turing", "readability"}
    gee = tests[tests.test == "GEE rate vs chance"].iloc[0]
    assert gee.ci_low < gee.estimate < gee.ci_high and gee.p_value < 0.05 and gee.clusters == 40


def test_a_failed_mixed_model_is_reported_not_raised(monkeypatch):
    failed = pd.DataFrame(
        [
            dict.fromkeys(S.MIXED_COLUMNS, float("nan"))
            | {"term": "(model)", "type": "", "status": "failed: ValueError: no"}
        ]
    )
    monkeypatch.setattr(S, "mixed_logit", lambda *a, **k: failed)
    table, _ = simulate_turing(20, 0.3, seed=3)
    md = build_report(analyze_table(table, AnalysisSettings())).markdown()
    assert (
        "> **Warning:** The crossed mixed logit (participants x words) could not be fitted: ValueError: no."
        in md
    )


def test_gee_interval_covers_the_truth_at_its_level_where_the_naive_one_does_not():
    gee, naive = [], []
    for seed in range(30):
        rows, _ = turing_rows(
            participants=40, rate=0.3, icc=0.25, attention_checks=0, seed=100 + seed
        )
        g = S.gee_rate(rows, "chose_robot", "participant_id", 0.2).iloc[0]
        b = S.binomial_test(rows, "chose_robot", 0.2, "two-sided").iloc[0]
        gee.append(g.ci_low <= 0.3 <= g.ci_high)
        naive.append(b.ci_low <= 0.3 <= b.ci_high)
    assert np.mean(gee) >= 0.85
    assert np.mean(naive) < np.mean(gee)
