"""Tests of ``studies.analysis.stats.parametric`` (moved from the suite on: studies.analysis
statistics: each function against the scipy/statsmodels call it names, and the paper's numbers
(shared/reference/studies.md) reproduced from the paper's summaries)."""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats
from statsmodels.stats.weightstats import ttost_paired

from studies.analysis import stats as S
from studies.analysis.paper import (
    paper_turing_frame,
)
from tests.helpers.study_analysis import close, fields, paired_frame  # noqa: F401 (fixtures)


def test_one_sample_ttest_on_rows_and_on_cluster_means_matches_scipy():
    df = paper_turing_frame()
    flat = S.one_sample_ttest(df, "confidence", 3, "greater").iloc[0]
    ref = stats.ttest_1samp(df["confidence"], 3, alternative="greater")
    ci = stats.ttest_1samp(df["confidence"], 3).confidence_interval(0.95)  # two-sided CI
    close(
        fields(flat, "statistic", "p_value", "estimate", "ci_low", "ci_high"),
        [ref.statistic, ref.pvalue, df["confidence"].mean(), ci.low, ci.high],
    )
    assert (flat.n, flat.df) == (500, 499)
    means = df.groupby("participant_id")["confidence"].mean()
    clus = S.one_sample_ttest(df, "confidence", 3, "two-sided", cluster="participant_id").iloc[0]
    ref = stats.ttest_1samp(means, 3)
    ci = stats.t.interval(0.95, 49, loc=means.mean(), scale=stats.sem(means))
    close(
        fields(clus, "statistic", "p_value", "estimate", "ci_low", "ci_high"),
        [ref.statistic, ref.pvalue, means.mean(), *ci],
    )
    assert (clus.n, clus.clusters, clus.df) == (50, 50, 49)


def test_paired_tests_match_ttest_rel_ttost_paired_and_one_sided_ttest(paired_frame):
    out = S.paired_tests(paired_frame, "correct", "writer", "participant_id", margin=0.1)
    wide = paired_frame.pivot_table(index="participant_id", columns="writer", values="correct")
    r, h = wide["robot"].to_numpy(), wide["human"].to_numpy()
    d = r - h
    ref = stats.ttest_rel(r, h)
    ci95, ci90 = ref.confidence_interval(0.95), ref.confidence_interval(0.90)
    close(
        fields(out.iloc[0], "estimate", "ci_low", "ci_high", "statistic", "p_value"),
        [d.mean(), ci95.low, ci95.high, ref.statistic, ref.pvalue],
    )
    p, lo, up = ttost_paired(r, h, -0.1, 0.1)
    close(
        fields(out.iloc[1], "estimate", "ci_low", "ci_high", "p_value", "p_lower", "p_upper"),
        [d.mean(), ci90.low, ci90.high, p, lo[1], up[1]],
    )
    close(out.iloc[1].statistic, min(abs(lo[0]), abs(up[0])))
    ni = stats.ttest_1samp(d, -0.1, alternative="greater")
    close(
        fields(out.iloc[2], "estimate", "ci_low", "statistic", "p_value"),
        [d.mean(), ci90.low, ni.statistic, ni.pvalue],
    )
    assert out.iloc[2].ci_high == np.inf
    assert out.n.tolist() == [20] * 3 and out.df.tolist() == [19] * 3
    assert list(out.test) == [
        "paired t-test by participant (robot - human)",
        "paired TOST by participant (±0.1)",
        "non-inferiority by participant (margin 0.1)",
    ]


def test_paired_tests_drop_clusters_seeing_one_writer_only(paired_frame):
    lone = pd.DataFrame([dict(participant_id="solo", word="w0", writer="human", correct=1.0)])
    out = S.paired_tests(pd.concat([paired_frame, lone]), "correct").iloc[0]
    assert out.n == 20 and "1 dropped" in out.method


def test_zero_variance_tests_are_not_estimable_rather_than_p_zero():
    same = pd.DataFrame({"participant_id": range(8), "v": 5.0})
    t = S.one_sample_ttest(same, "v", 3, "two-sided", cluster="participant_id").iloc[0]
    assert t.estimate == 5 and np.isnan([t.p_value, t.ci_low, t.statistic]).all()
    assert "zero variance" in t.conclusion
    # round-off in the means (1/3 vs 2/6) is no variance either
    thirds = pd.DataFrame(
        {"participant_id": [0, 0, 0, 1, 1, 1, 1, 1, 1], "v": [1, 0, 0, 1, 1, 0, 0, 0, 0]}
    )
    assert np.isnan(S.one_sample_ttest(thirds, "v", 0.2, cluster="participant_id").p_value.iloc[0])
    # one value spread is enough: a real t-test
    spread = pd.DataFrame({"participant_id": range(8), "v": [5.0] * 7 + [4.0]})
    assert np.isfinite(S.one_sample_ttest(spread, "v", 3, cluster="participant_id").p_value.iloc[0])
