"""Tests of ``studies.analysis.stats.nonparametric``: the signed-rank test of cluster means against
scipy's ``wilcoxon`` on the differences, zero differences dropped."""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

from studies.analysis import stats as S
from tests.helpers.study_analysis import close, fields

RATINGS = pd.DataFrame(
    {
        "participant_id": list("aabbccddeeffgg"),
        "word": list("xyxyxyxyxyxyxy"),
        "confidence": [4, 5, 3, 3, 5, 4, 2, 4, 5, 5, 4, 3, 1, 2],
    }
)


def test_signed_rank_matches_wilcoxon_on_the_nonzero_differences_of_cluster_means():
    row = S.signed_rank_test(RATINGS, "confidence", 3, "participant_id", alpha=0.1).iloc[0]
    means = RATINGS.groupby("participant_id")["confidence"].mean().to_numpy()
    d = means - 3
    ref = stats.wilcoxon(d[d != 0])  # participant b's mean is 3: dropped
    close(fields(row, "statistic", "p_value"), [ref.statistic, ref.pvalue])
    assert row.estimate == np.median(means) and row.n == 7 and row.clusters == 7
    assert row.alpha == 0.1 and bool(row.reject) == (ref.pvalue < 0.1)
    assert row.test == "Wilcoxon signed-rank vs 3 on participant means"
    assert row.null_hypothesis == "median = 3"
    assert row.method == "scipy wilcoxon (two-sided), zero differences dropped"


def test_signed_rank_defaults_other_centre_and_cluster():
    default = S.signed_rank_test(RATINGS).iloc[0]
    explicit = S.signed_rank_test(RATINGS, "confidence", 3.0, "participant_id", 0.05).iloc[0]
    assert default.equals(explicit)
    by_word = S.signed_rank_test(RATINGS, popmean=2.5, cluster="word").iloc[0]
    means = RATINGS.groupby("word")["confidence"].mean().to_numpy()
    ref = stats.wilcoxon(means - 2.5)
    close(by_word.p_value, ref.pvalue)
    assert by_word.test == "Wilcoxon signed-rank vs 2.5 on word means" and by_word.n == 2


def test_signed_rank_words_the_conclusion_by_side():
    high = pd.DataFrame({"participant_id": range(8), "confidence": [5, 4, 5, 4, 5, 4, 5, 5]})
    row = S.signed_rank_test(high).iloc[0]
    assert row.reject and row.conclusion.startswith("median 5.00 > 3 (p = ")
    low = high.assign(confidence=6 - high.confidence)
    row = S.signed_rank_test(low).iloc[0]
    assert row.reject and row.conclusion.startswith("median 1.00 < 3 (p = ")
    mixed = high.assign(confidence=[2, 4, 2, 4, 3, 4, 2, 3])
    row = S.signed_rank_test(mixed).iloc[0]
    assert not row.reject and row.conclusion.startswith("not shown to differ from 3 (p = ")


def test_signed_rank_when_every_mean_is_the_centre_is_not_estimable():
    flat = pd.DataFrame({"participant_id": list("aabb"), "confidence": [2, 4, 3, 3]})
    row = S.signed_rank_test(flat).iloc[0]
    assert row.conclusion == "not estimable: every mean equals the neutral value" and row.n == 2
    one = S.signed_rank_test(flat.iloc[:2]).iloc[0]
    assert one.conclusion.startswith("not estimable") and one.n == 1
    single = S.signed_rank_test(pd.DataFrame({"participant_id": ["a"], "confidence": [4]})).iloc[0]
    assert np.isfinite(single.p_value) and single.n == 1  # one nonzero difference is a test


def test_signed_rank_not_estimable_row_names_its_test():
    flat = pd.DataFrame({"participant_id": list("aabb"), "confidence": [2, 4, 3, 3]})
    row = S.signed_rank_test(flat).iloc[0]
    assert row.test == "Wilcoxon signed-rank vs 3 on participant means"
