"""Tests of ``studies.analysis.stats.proportions`` (moved from the suite on: studies.analysis
statistics: each function against the scipy/statsmodels call it names, and the paper's numbers
(shared/reference/studies.md) reproduced from the paper's summaries)."""

from __future__ import annotations

import pandas as pd
import pytest
from scipy import stats
from statsmodels.stats.proportion import proportion_confint

from studies.analysis import stats as S
from studies.analysis.paper import (
    paper_turing_frame,
)
from tests.helpers.study_analysis import binary_frame, close, fields

# --------------------------------------------------------------------------- reference values


def test_binomial_test_matches_scipy_binomtest_with_two_sided_exact_ci():
    row = S.binomial_test(binary_frame(211, 500), "y", 0.2, "greater").iloc[0]
    ref = stats.binomtest(211, 500, 0.2, alternative="greater")
    ci = stats.binomtest(211, 500, 0.2).proportion_ci(method="exact")
    close(fields(row, "p_value", "ci_low", "ci_high"), [ref.pvalue, ci.low, ci.high], 1e-12)
    assert row.estimate == 211 / 500 and row.ci_level == 0.95
    assert row.reject and row.statistic == 211 and row.n == 500


def test_proportion_intervals_match_statsmodels_proportion_confint():
    out = S.proportion_intervals(binary_frame(211, 500), "y").set_index("method")
    for method in ("beta", "wilson"):
        close(
            out.loc[method, ["ci_low", "ci_high"]].to_numpy(dtype=float),
            proportion_confint(211, 500, method=method),
            1e-12,
        )
        assert out.loc[method, ["k", "n", "rate"]].tolist() == [211, 500, 211 / 500]


def test_statistics_name_a_missing_column():
    with pytest.raises(KeyError, match="column 'chose' not in the frame"):
        S.binomial_test(paper_turing_frame(), "chose")


@pytest.mark.parametrize("k", [0, 7])  # a word nobody / everybody got: real outcomes
def test_boundary_rates_get_intervals_that_contain_them(k):
    from studies.analysis.report import fig_turing_words
    from studies.analysis.stats import proportion_ci, rates_by

    rows = [{"word": "all", "chose_robot": int(i < k)} for i in range(7)]
    rows += [{"word": "some", "chose_robot": int(i < 3)} for i in range(7)]
    per_word = rates_by(pd.DataFrame(rows), "chose_robot", "word", chance=0.2)
    edge = per_word.set_index("word").loc["all"]
    assert edge["rate"] == k / 7
    assert edge["ci_low"] <= edge["rate"] <= edge["ci_high"]
    assert (edge["ci_low"], edge["ci_high"])[k == 7] == k / 7  # the bound is the rate itself
    # away from the boundary the interval is statsmodels' own
    assert proportion_ci(3, 7) == pytest.approx(proportion_confint(3, 7, method="wilson"))
    fig = fig_turing_words(per_word, chance=0.2, margin=0.1, overall=None)  # no negative bars
    assert fig is not None
