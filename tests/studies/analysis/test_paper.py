"""Tests of ``studies.analysis.paper`` (moved from the suite on: studies.analysis statistics: each
function against the scipy/statsmodels call it names, and the paper's numbers
(shared/reference/studies.md) reproduced from the paper's summaries)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import statsmodels.api as sm
from numpy.testing import assert_allclose
from scipy import stats
from statsmodels.stats.multitest import multipletests
from statsmodels.stats.proportion import proportion_confint
from statsmodels.stats.weightstats import ttost_paired

from studies.analysis import stats as S
from studies.analysis.paper import (
    PAPER,
    h2_threshold,
    paired_from_summary,
    paper_readability_frame,
    paper_turing_frame,
    reproduce_paper,
)
from tests.helpers.study_analysis import close, fields


def test_group_ttest_is_scipy_ttest_ind_on_the_unit_rates():
    df = paper_readability_frame()
    row = S.group_ttest(df, "correct", "writer", "word").iloc[0]
    rates = df.groupby(["writer", "word"])["correct"].mean()
    ref = stats.ttest_ind(rates["robot"], rates["human"])
    ci = ref.confidence_interval(0.95)
    close(
        fields(row, "statistic", "p_value", "estimate", "ci_low", "ci_high"),
        [ref.statistic, ref.pvalue, rates["robot"].mean() - rates["human"].mean(), ci.low, ci.high],
    )
    assert (row.df, row.n) == (18, 20)


def test_group_ttest_without_both_levels_is_not_estimable():
    df = paper_readability_frame()
    row = S.group_ttest(df[df.writer == "human"], "correct").iloc[0]
    assert row.conclusion.startswith("not estimable") and np.isnan(row.p_value)


def test_gee_rate_matches_statsmodels_gee_with_offset_at_chance():
    df = paper_turing_frame()
    rows = S.gee_rate(df, "chose_robot", "participant_id", 0.2, margin=0.05)
    off = np.full(len(df), np.log(0.2 / 0.8))
    ref = sm.GEE(
        df["chose_robot"],
        np.ones((len(df), 1)),
        groups=pd.factorize(df.participant_id)[0],
        family=sm.families.Binomial(),
        cov_struct=sm.cov_struct.Exchangeable(),
        offset=off,
    ).fit(cov_type="bias_reduced")
    b, se = ref.params.iloc[0], ref.bse.iloc[0]
    assert ref.pvalues.iloc[0] < 1e-30  # far from chance: only a relative comparison checks it
    q, q2 = stats.norm.ppf(0.975), stats.norm.ppf(0.95)
    expit = lambda x: 1 / (1 + np.exp(-x))  # noqa: E731
    close(
        fields(rows.iloc[0], "estimate", "ci_low", "ci_high", "statistic", "p_value"),
        [
            expit(off[0] + b),
            expit(off[0] + b - q * se),
            expit(off[0] + b + q * se),
            b / se,
            ref.pvalues.iloc[0],
        ],
        1e-7,
    )
    assert rows.iloc[0].estimate == pytest.approx(211 / 500)  # equal cluster sizes: the sample rate
    lo_b, up_b = np.log(0.15 / 0.85) - off[0], np.log(0.25 / 0.75) - off[0]
    p_low, p_upp = stats.norm.sf((b - lo_b) / se), stats.norm.cdf((b - up_b) / se)
    close(
        fields(
            rows.iloc[1],
            "estimate",
            "ci_low",
            "ci_high",
            "statistic",
            "p_value",
            "p_lower",
            "p_upper",
        ),
        [
            expit(off[0] + b),
            expit(off[0] + b - q2 * se),
            expit(off[0] + b + q2 * se),
            b / se,
            max(p_low, p_upp),
            p_low,
            p_upp,
        ],
        1e-7,
    )
    assert (
        rows.iloc[0].reject and rows.clusters.tolist() == [50, 50] and rows.n.tolist() == [500] * 2
    )


def test_rates_by_matches_wilson_intervals_exact_tests_and_holm():
    df = paper_turing_frame()
    out = S.rates_by(df, "chose_robot", "word", chance=0.2)
    assert list(out.k) == [17, 19, 20, 20, 21, 21, 21, 22, 22, 28]
    lo, hi = proportion_confint(out.k, out.n, method="wilson")
    assert_allclose(out.ci_low, lo) and assert_allclose(out.ci_high, hi)
    p = [stats.binomtest(k, 50, 0.2).pvalue for k in out.k]
    assert_allclose(out.p_vs_chance, p)
    assert_allclose(out.p_holm, multipletests(p, method="holm")[1])


def test_signed_rank_test_is_scipy_wilcoxon_on_participant_means():
    df = paper_turing_frame()
    row = S.signed_rank_test(df, "confidence", 3, "participant_id").iloc[0]
    means = df.groupby("participant_id")["confidence"].mean()
    d = means - 3
    ref = stats.wilcoxon(d[d != 0])
    close(
        fields(row, "statistic", "p_value", "estimate"), [ref.statistic, ref.pvalue, means.median()]
    )


# --------------------------------------------------------------------------- the paper, reproduced


@pytest.fixture(scope="module")
def reproduced() -> pd.DataFrame:
    return reproduce_paper(allocation_reps=50).set_index("quantity")


@pytest.mark.parametrize(
    ("quantity", "shown"),
    [
        ("robot picks k / n", "211/500 = 0.422"),
        ("exact binomial test vs 0.2 (greater): p", "1.3e-29"),
        ("95 % CI exact (Clopper-Pearson)", "[0.378, 0.467]"),
        ("95 % CI Wilson", "[0.379, 0.466]"),
        ("binomial TOST on (0.143, 0.257): p", "1.0"),
        ("counts that could show equivalence at ±0.057, n = 500", "86 <= k <= 112 of 500"),
        ("SD across the 10 words' rates", "0.057"),
        ("power of 500 independent trials, TOST ±0.05, true 0.20", "0.73"),
        ("H2 t-test vs 3 on all 500 ratings: t", "2.53"),
        ("H2 t-test vs 3 on all 500 ratings: p", "0.0058"),
        ("H2 on participant means: largest SD of means that still rejects", "0.717"),
        ("H2 on participant means: largest ICC that still rejects", "0.14"),
        (
            "independent t-test on 10 word rates per writer (from the summaries): p",
            "0.218 (t = 1.28, df 18)",
        ),
        ("correct words, human vs PRG", "117/150 vs 125/150"),
    ],
)
def test_reproduced_paper_number_matches_studies_md(reproduced, quantity, shown):
    assert reproduced.loc[quantity, "shown"] == shown


def test_paired_reanalysis_of_study_2_matches_studies_md(reproduced):
    tost = reproduced.loc["paired TOST ±0.10: p", "value"]
    ni = reproduced.loc["non-inferiority (PRG >= human - 0.10): p", "value"]
    assert tost == pytest.approx(0.2, abs=0.03) and tost > 0.05  # equivalence not shown
    assert ni == pytest.approx(0.005, abs=0.002)  # non-inferiority shown
    lo, hi = (
        float(x) for x in reproduced.loc["paired TOST ±0.10: p", "note"].split(": ")[-1].split("-")
    )
    assert 0.05 < lo < 0.2 < hi < 0.3  # over allocations the TOST never shows equivalence
    assert reproduced.loc[
        "independent t-test on the rebuilt word rates: p", "value"
    ] == pytest.approx(0.2, abs=0.03)


def test_paired_from_summary_agrees_with_ttost_paired_on_data_with_that_mean_and_sd():
    z = np.random.default_rng(0).normal(size=30)
    d = 0.0533 + 0.30 * (z - z.mean()) / z.std(ddof=1)
    p, lo, _ = ttost_paired(d, np.zeros(30), -0.1, 0.1)
    got = paired_from_summary(0.0533, 0.30, 30, 0.1)
    close([got["p_tost"], got["p_noninferiority"]], [p, lo[1]])
    assert got["p_tost"] == pytest.approx(0.2, abs=0.01) and got[
        "p_noninferiority"
    ] == pytest.approx(0.0045, abs=5e-4)


def test_h2_threshold_separates_rejecting_from_non_rejecting_participant_means():
    s_max, icc = h2_threshold()
    assert (s_max, icc) == pytest.approx((0.717, 0.143), abs=1e-3)
    z = np.random.default_rng(0).normal(size=50)
    for sd, rejects in ((s_max * 0.98, True), (s_max * 1.02, False)):
        means = PAPER["confidence_mean"] + sd * (z - z.mean()) / z.std(ddof=1)
        frame = pd.DataFrame({"participant_id": range(50), "confidence": means})
        assert (
            S.one_sample_ttest(frame, "confidence", 3, "greater", cluster="participant_id")
            .iloc[0]
            .reject
            == rejects
        )
