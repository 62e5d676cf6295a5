"""Tests of ``studies.analysis.stats.reliability`` (moved from the suite on: studies.analysis
statistics: each function against the scipy/statsmodels call it names, and the paper's numbers
(shared/reference/studies.md) reproduced from the paper's summaries)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from studies.analysis import stats as S


def test_icc_oneway_matches_the_anova_formula():
    df = pd.DataFrame({"g": np.repeat([0, 1, 2], 3), "v": [1, 2, 3, 4, 5, 6, 8, 9, 7]})
    out = S.icc_oneway(df, "v", "g").iloc[0]
    msb = 3 * ((2 - 5) ** 2 + (5 - 5) ** 2 + (8 - 5) ** 2) / 2
    msw = 6 / 6
    assert out.icc == pytest.approx((msb - msw) / (msb + 2 * msw))
    assert out.design_effect == pytest.approx(1 + 2 * out.icc)


def test_icc_oneway_with_unequal_clusters_uses_the_anova_mean_size():
    v = [1.0, 3.0, 4.0, 6.0, 5.0, 9.0, 8.0, 10.0, 7.0]
    g = ["a", "a", "b", "b", "b", "c", "c", "c", "c"]
    out = S.icc_oneway(pd.DataFrame({"g": g, "v": v}), "v", "g").iloc[0]
    groups = {"a": [1.0, 3.0], "b": [4.0, 6.0, 5.0], "c": [9.0, 8.0, 10.0, 7.0]}
    grand = np.mean(v)
    ssb = sum(len(x) * (np.mean(x) - grand) ** 2 for x in groups.values())
    ssw = sum(((np.array(x) - np.mean(x)) ** 2).sum() for x in groups.values())
    msb, msw = ssb / 2, ssw / 6
    n0 = (9 - (4 + 9 + 16) / 9) / 2
    icc = (msb - msw) / (msb + (n0 - 1) * msw)
    assert out.icc == pytest.approx(icc, rel=1e-12)
    assert (out.value, out.clusters, out.n) == ("v", 3, 9)
    assert out.mean_cluster_size == 3.0
    assert out.design_effect == pytest.approx(1 + 2 * icc, rel=1e-12)


def test_icc_oneway_drops_missing_values_and_defaults_to_participants():
    df = pd.DataFrame(
        {"participant_id": [0, 0, 0, 1, 1, 1, 2, 2], "v": [1, 2, None, 4, 6, "x", 9, 7]}
    )
    out = S.icc_oneway(df, "v").iloc[0]
    ref = S.icc_oneway(pd.DataFrame({"g": [0, 0, 1, 1, 2, 2], "v": [1, 2, 4, 6, 9, 7]}), "v", "g")
    assert out.icc == pytest.approx(ref.icc.iloc[0], rel=1e-12) and out.n == 6
    assert out.mean_cluster_size == 2.0


def test_icc_below_zero_gives_design_effect_one_and_degenerate_cases_nan():
    neg = pd.DataFrame({"g": [0, 0, 1, 1], "v": [1.0, 3.0, 1.0, 3.0]})  # no between variance
    out = S.icc_oneway(neg, "v", "g").iloc[0]
    assert out.icc == pytest.approx(-1.0) and out.design_effect == 1.0
    one = S.icc_oneway(pd.DataFrame({"g": [0, 0, 0], "v": [1.0, 2.0, 4.0]}), "v", "g").iloc[0]
    assert np.isnan(one.icc) and np.isnan(one.design_effect) and one.mean_cluster_size == 3.0
    singles = S.icc_oneway(pd.DataFrame({"g": [0, 1, 2], "v": [1.0, 2.0, 4.0]}), "v", "g").iloc[0]
    assert np.isnan(singles.icc) and singles.clusters == 3 and singles.n == 3
    flat = S.icc_oneway(pd.DataFrame({"g": [0, 0, 1, 1], "v": [2.0] * 4}), "v", "g").iloc[0]
    assert np.isnan(flat.icc)  # 0 / 0: no variance at all
    empty = S.icc_oneway(pd.DataFrame({"g": [0], "v": [None]}), "v", "g").iloc[0]
    assert empty.clusters == 0 and np.isnan(empty.mean_cluster_size)


def test_icc_needs_one_more_row_than_clusters_and_ignores_other_missing_columns():
    # sizes 2, 1, 1: n - k = 1 degree of freedom within, enough for MSW
    df = pd.DataFrame({"g": ["a", "a", "b", "c"], "v": [1.0, 3.0, 5.0, 9.0], "note": np.nan})
    out = S.icc_oneway(df, "v", "g").iloc[0]
    grand = 4.5
    ssb = 2 * (2 - grand) ** 2 + (5 - grand) ** 2 + (9 - grand) ** 2
    msb, msw = ssb / 2, 2.0 / 1
    n0 = (4 - (4 + 1 + 1) / 4) / 2
    assert out.icc == pytest.approx((msb - msw) / (msb + (n0 - 1) * msw), rel=1e-12)
    assert out.n == 4


def test_icc_is_scale_free_small_values_included():
    df = pd.DataFrame({"g": np.repeat([0, 1, 2], 3), "v": [1, 2, 3, 4, 5, 6, 8, 9, 7]})
    tiny = df.assign(v=df.v * 1e-3)  # every mean square below 1
    big, small = S.icc_oneway(df, "v", "g").iloc[0], S.icc_oneway(tiny, "v", "g").iloc[0]
    assert small.icc == pytest.approx(big.icc, rel=1e-9)
    assert small.design_effect == pytest.approx(big.design_effect, rel=1e-9)
