"""Tests of ``studies.analysis.stats.equivalence`` (moved from the suite on: studies.analysis
statistics: each function against the scipy/statsmodels call it names, and the paper's numbers
(shared/reference/studies.md) reproduced from the paper's summaries)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import stats
from statsmodels.stats.proportion import binom_tost, binom_tost_reject_interval, proportion_confint

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


# --------------------------------------------------------------------------- every branch


def test_tost_conclusion_names_each_null_kept_or_the_band_shown():
    from studies.analysis.stats.equivalence import tost_conclusion

    shown = tost_conclusion("rate", 0.01, 0.001, 0.01, 0.15, 0.25, 0.05)
    assert shown == "equivalent: rate within (0.15, 0.25) (p = 0.010)"
    both = tost_conclusion("rate", 0.4, 0.3, 0.4, 0.15, 0.25, 0.05)
    assert both == (
        "equivalence not shown: null 'rate <= 0.15' (p = 0.300) and "
        "'rate >= 0.25' (p = 0.400) not rejected"
    )
    low = tost_conclusion("d", 0.05, 0.05, 0.049, -0.1, 0.1, 0.05)  # p = alpha is kept
    assert low == "equivalence not shown: null 'd <= -0.1' (p = 0.050) not rejected"
    upp = tost_conclusion("d", 0.2, 0.001, 0.2, -0.1, 0.1, 0.05)
    assert upp == "equivalence not shown: null 'd >= 0.1' (p = 0.200) not rejected"


def test_tost_fields_report_the_1_minus_2_alpha_interval_and_both_p_values():
    from studies.analysis.stats.equivalence import tost_fields

    out = tost_fields("d", (-0.05, 0.04), 0.03, 0.01, 0.03, -0.1, 0.1, 0.1)
    assert out == dict(
        ci_low=-0.05,
        ci_high=0.04,
        ci_level=pytest.approx(0.8),
        p_value=0.03,
        p_lower=0.01,
        p_upper=0.03,
        reject=True,
        conclusion="equivalent: d within (-0.1, 0.1) (p = 0.030)",
    )
    assert tost_fields("d", (0, 1), 0.1, 0.1, 0.0, -0.1, 0.1, 0.1)["reject"] is False


def test_noninferiority_fields_are_one_sided_from_the_lower_bound():
    from studies.analysis.stats.equivalence import noninferiority_fields

    out = noninferiority_fields("r - h", 0.1, -0.04, 0.02, 0.05, "no worse")
    assert out == dict(
        null_hypothesis="r - h <= -0.1",
        ci_low=-0.04,
        ci_high=np.inf,
        ci_level=0.95,
        p_value=0.02,
        reject=True,
        conclusion="no worse (p = 0.020)",
    )
    kept = noninferiority_fields("r - h", 0.1, -0.2, 0.3, 0.05, "no worse")
    assert kept["conclusion"] == "non-inferiority not shown (p = 0.300)" and not kept["reject"]


def test_binomial_tost_at_another_level_and_with_its_defaults():
    row = S.binomial_tost(binary_frame(40, 200), "y", 0.2, 0.05, alpha=0.1).iloc[0]
    p, p_low, p_upp = binom_tost(40, 200, 0.15, 0.25)
    close(fields(row, "p_value", "p_lower", "p_upper"), [p, p_low, p_upp], 1e-12)
    close(fields(row, "ci_low", "ci_high"), proportion_confint(40, 200, 0.2, method="beta"), 1e-12)
    assert row.ci_level == pytest.approx(0.8) and row.alpha == 0.1
    assert bool(row.reject) == (p < 0.1)
    lo, hi = binom_tost_reject_interval(0.15, 0.25, 200, alpha=0.1)
    assert f"{lo:.0f} <= k <= {hi:.0f} of 200" in row.method
    assert row.null_hypothesis == "rate <= 0.15 or rate >= 0.25"
    assert row.test == "exact binomial TOST vs chance"
    df = pd.DataFrame({"chose_robot": [1] * 20 + [0] * 80})
    default = S.binomial_tost(df).iloc[0]
    close(default.p_value, binom_tost(20, 100, 0.15, 0.25)[0], 1e-12)
    assert default.alpha == 0.05 and default.null_hypothesis == "rate <= 0.15 or rate >= 0.25"


def test_margin_warnings_tolerance_is_relative_and_ignores_non_positive_values():
    cands = {"the SE": 0.05, "a zero": 0.0, "a nan": float("nan"), "a negative": -0.05}
    assert len(S.margin_warnings(0.0549, "unstated", cands)) == 1  # within 10 %: close
    assert S.margin_warnings(0.0551, "unstated", cands) == []
    assert len(S.margin_warnings(0.0451, "unstated", cands)) == 1
    assert S.margin_warnings(0.0449, "unstated", cands) == []
    halves = {"half": 0.5}  # binary fractions: the edge itself is exact
    assert len(S.margin_warnings(0.75, "unstated", halves, tolerance=0.5)) == 1
    assert len(S.margin_warnings(0.25, "unstated", halves, tolerance=0.5)) == 1
    assert len(S.margin_warnings(0.06, "unstated", cands, tolerance=0.2)) == 1
    assert S.margin_warnings(0.0, "unstated", cands) == []
    assert S.margin_warnings(-0.05, "unstated", cands) == []
    assert S.margin_warnings(0.05, "unstated") == []
    assert S.margin_warnings(0.05, "preregistered") == []
    warn = S.margin_warnings(0.05, "unstated", {"the SE": 0.05, "the half-width": 0.049})
    assert len(warn) == 2 and "close to the SE of these data (0.050)" in warn[0]
    assert warn[0].startswith("the margin 0.05 (source not stated)")
    assert S.margin_warnings(0.06, "data")[0].startswith("the equivalence margin 0.06 was derived")
    assert S.margin_warnings(0.06, "default")[0].startswith(
        "no equivalence margin was configured; the default 0.06 was used"
    )


def test_margin_candidates_are_the_wald_half_width_the_se_and_the_word_sd():
    df = pd.DataFrame({"word": [*"aaabbbccc", "d"], "y": [1, 1, 0, 0, 0, 0, 1, 1, 1, np.nan]})
    p, n = 5 / 9, 9
    se = np.sqrt(p * (1 - p) / n)
    out = S.margin_candidates(df, "y", alpha=0.1)
    close(out["the standard error"], se)
    close(out["the CI half-width"], stats.norm.ppf(0.95) * se)
    close(out["the SD across words"], np.std([2 / 3, 0, 1], ddof=1))
    assert set(out) == {"the standard error", "the CI half-width", "the SD across words"}
    close(S.margin_candidates(df, "y")["the CI half-width"], stats.norm.ppf(0.975) * se)
    assert "the SD across words" not in S.margin_candidates(df, "y", word=None)
    assert "the SD across words" not in S.margin_candidates(df.drop(columns="word"), "y")
    one_word = S.margin_candidates(df.assign(word="a"), "y")
    assert "the SD across words" not in one_word and "the standard error" in one_word
    assert S.margin_candidates(pd.DataFrame({"word": ["a"], "y": [1]}), "y") == {}


def test_tost_conclusion_keeps_a_null_whose_p_is_exactly_alpha():
    from studies.analysis.stats.equivalence import tost_conclusion

    text = tost_conclusion("rate", 0.05, 0.01, 0.05, 0.15, 0.25, 0.05)
    assert text == "equivalence not shown: null 'rate >= 0.25' (p = 0.050) not rejected"
    low = tost_conclusion("rate", 0.05, 0.05, 0.01, 0.15, 0.25, 0.05)
    assert low == "equivalence not shown: null 'rate <= 0.15' (p = 0.050) not rejected"


def test_binomial_tost_row_counts_its_trials():
    row = S.binomial_tost(binary_frame(40, 200), "y").iloc[0]
    assert row.n == 200 and row.estimate == 0.2 and row.statistic == 40


def test_margin_candidates_from_two_answers_and_two_words():
    df = pd.DataFrame({"word": ["a", "b"], "y": [1.0, 0.0]})
    out = S.margin_candidates(df, "y")
    close(out["the standard error"], np.sqrt(0.25 / 2))
    close(out["the SD across words"], np.std([1.0, 0.0], ddof=1))
