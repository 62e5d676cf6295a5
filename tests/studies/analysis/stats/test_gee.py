"""Tests of ``studies.analysis.stats.gee`` (moved from the suite on: studies.analysis statistics:
each function against the scipy/statsmodels call it names, and the paper's numbers
(shared/reference/studies.md) reproduced from the paper's summaries)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import statsmodels.api as sm
from scipy import stats

from studies.analysis import stats as S
from tests.helpers.study_analysis import binary_frame, close, fields, paired_frame  # noqa: F401 (fixtures)


def test_gee_tost_rejects_exactly_when_its_90_percent_ci_is_inside_the_band():
    for k in (95, 100, 112, 125):
        row = S.gee_rate(binary_frame(k, 600, 60), "y", "participant_id", 0.2, margin=0.05).iloc[1]
        inside = row.ci_low > 0.15 and row.ci_high < 0.25
        assert bool(row.reject) == inside, k


def test_gee_rate_reports_instead_of_raising_when_every_answer_is_the_same():
    rows = S.gee_rate(binary_frame(0, 100), "y", "participant_id", 0.2, margin=0.05)
    assert len(rows) == 2 and rows.conclusion.str.startswith("not estimable").all()


def test_gee_rate_with_one_participant_is_not_estimable_rather_than_overconfident():
    one = binary_frame(6, 10, participants=1)
    row = S.gee_rate(one, "y", "participant_id", 0.2).iloc[0]
    assert row.conclusion == "not estimable: needs answers from at least 2 participants"
    few = S.gee_rate(binary_frame(30, 100, participants=10), "y", "participant_id", 0.2).iloc[0]
    assert "fewer than 20 clusters" in few.method


def test_gee_difference_is_the_difference_in_rates_with_cluster_robust_se(paired_frame):
    rows = S.gee_difference(paired_frame, "correct", "writer", "participant_id", margin=0.1)
    means = paired_frame.groupby("writer")["correct"].mean()
    assert rows.iloc[0].estimate == pytest.approx(means["robot"] - means["human"])
    x = (paired_frame.writer == "robot").astype(float)
    ref = sm.GEE(
        paired_frame["correct"],
        np.column_stack([np.ones(len(x)), x]),
        groups=pd.factorize(paired_frame.participant_id)[0],
        family=sm.families.Gaussian(),
        cov_struct=sm.cov_struct.Exchangeable(),
    ).fit(cov_type="bias_reduced")
    d, se = ref.params.iloc[1], ref.bse.iloc[1]
    q, q2 = stats.norm.ppf(0.975), stats.norm.ppf(0.95)
    close(
        fields(rows.iloc[0], "estimate", "ci_low", "ci_high", "statistic", "p_value"),
        [d, d - q * se, d + q * se, d / se, ref.pvalues.iloc[1]],
        1e-7,
    )
    p1, p2 = stats.norm.sf((d + 0.1) / se), stats.norm.cdf((d - 0.1) / se)
    close(
        fields(rows.iloc[1], "estimate", "ci_low", "ci_high", "p_value", "p_lower", "p_upper"),
        [d, d - q2 * se, d + q2 * se, max(p1, p2), p1, p2],
        1e-7,
    )
    close(
        fields(rows.iloc[2], "estimate", "ci_low", "statistic", "p_value"),
        [d, d - q2 * se, (d + 0.1) / se, p1],
        1e-7,
    )
    assert rows.iloc[2].ci_high == np.inf
    assert list(rows.test) == [
        "GEE difference (robot - human)",
        "GEE TOST (±0.1)",
        "GEE non-inferiority (margin 0.1)",
    ]
