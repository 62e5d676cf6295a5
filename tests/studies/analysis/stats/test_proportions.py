"""Tests of ``studies.analysis.stats.proportions`` (moved from the suite on: studies.analysis
statistics: each function against the scipy/statsmodels call it names, and the paper's numbers
(shared/reference/studies.md) reproduced from the paper's summaries)."""

from __future__ import annotations

import numpy as np
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


# --------------------------------------------------------------------------- every argument


def test_proportion_ci_at_another_level_and_method_and_on_arrays():
    close(
        proportion_ci_pair(S.proportion_ci(7, 20, 0.1, "beta")),
        proportion_confint(7, 20, 0.1, "beta"),
    )
    close(proportion_ci_pair(S.proportion_ci(7, 20)), proportion_confint(7, 20, 0.05, "wilson"))
    k, n = np.array([0, 3, 9]), np.array([9, 9, 9])
    lo, hi = S.proportion_ci(k, n, alpha=0.2)
    ref_lo, ref_hi = proportion_confint(k, n, 0.2, "wilson")
    close(lo[1:], ref_lo[1:])
    close(hi[:2], ref_hi[:2])
    assert lo[0] == 0.0 and hi[2] == 1.0 and isinstance(lo, np.ndarray)
    assert isinstance(S.proportion_ci(3, 9)[0], float)


def proportion_ci_pair(pair):
    return [float(pair[0]), float(pair[1])]


@pytest.mark.parametrize(
    "alternative, null, side",
    [
        ("greater", "rate <= 0.3", ">"),
        ("less", "rate >= 0.3", "<"),
        ("two-sided", "rate = 0.3", "!="),
    ],
)
def test_binomial_test_every_alternative_and_level(alternative, null, side):
    row = S.binomial_test(binary_frame(36, 100), "y", 0.3, alternative, alpha=0.2).iloc[0]
    ref = stats.binomtest(36, 100, 0.3, alternative=alternative)
    ci = stats.binomtest(36, 100, 0.3).proportion_ci(confidence_level=0.8, method="exact")
    close(fields(row, "p_value", "ci_low", "ci_high"), [ref.pvalue, ci.low, ci.high], 1e-12)
    assert row.null_hypothesis == null and row.alpha == 0.2 and row.ci_level == pytest.approx(0.8)
    assert bool(row.reject) == (ref.pvalue < 0.2)
    want = (
        f"rate 0.360 {side} chance 0.3" if row.reject else f"not shown that rate {side} chance 0.3"
    )
    assert row.conclusion.startswith(want + " (p = ")
    assert row.test == "exact binomial test vs chance"
    assert row.method == (
        f"scipy binomtest ({alternative}); two-sided Clopper-Pearson CI; trials independent"
    )


def test_binomial_test_defaults_are_the_papers_turing_question():
    df = pd.DataFrame({"chose_robot": [1] * 15 + [0] * 35})
    row = S.binomial_test(df).iloc[0]
    ref = stats.binomtest(15, 50, 0.2, alternative="greater")
    close(row.p_value, ref.pvalue, 1e-12)
    assert row.alpha == 0.05 and row.null_hypothesis == "rate <= 0.2"
    assert not row.reject and row.conclusion.startswith("not shown that rate > chance 0.2")


def test_proportion_intervals_every_method_and_level_with_defaults():
    df = pd.DataFrame({"chose_robot": [1] * 4 + [0] * 11})
    out = S.proportion_intervals(df)
    assert out.method.tolist() == ["beta", "wilson"] and (out.ci_level == 0.95).all()
    odd = S.proportion_intervals(df, alpha=0.1, methods=("agresti_coull", "jeffreys"))
    assert odd.method.tolist() == ["agresti_coull", "jeffreys"]
    for _, r in odd.iterrows():
        close([r.ci_low, r.ci_high], proportion_confint(4, 15, 0.1, r.method))
        assert (r.k, r.n, r.rate, r.ci_level) == (4, 15, 4 / 15, pytest.approx(0.9))


def test_rates_by_several_keys_with_tests_against_chance_and_holm():
    from statsmodels.stats.multitest import multipletests

    rows = []
    for word, writer, k, n in [
        ("a", "h", 1, 6),
        ("a", "r", 5, 6),
        ("b", "h", 2, 8),
        ("b", "r", 0, 5),
    ]:
        rows += [dict(word=word, writer=writer, y=float(i < k)) for i in range(n)]
    rows.append(dict(word="b", writer="r", y=np.nan))  # dropped
    out = S.rates_by(pd.DataFrame(rows), "y", ["word", "writer"], alpha=0.1, chance=0.25)
    assert out[["word", "writer"]].values.tolist() == [
        ["a", "h"],
        ["a", "r"],
        ["b", "h"],
        ["b", "r"],
    ]
    assert out.n.tolist() == [6, 6, 8, 5] and out.k.tolist() == [1, 5, 2, 0]
    close(out.rate, [1 / 6, 5 / 6, 2 / 8, 0])
    lo, hi = proportion_confint(out.k.to_numpy(), out.n.to_numpy(), 0.1, "wilson")
    close(out.ci_low[:3], lo[:3])
    close(out.ci_high, hi)
    assert out.ci_low.iloc[3] == 0.0
    close(out.ci_level, [0.9] * 4)
    p = [stats.binomtest(k, n, 0.25).pvalue for k, n in zip(out.k, out.n)]
    close(out.p_vs_chance, p)
    close(out.p_holm, multipletests(p, method="holm")[1])
    plain = S.rates_by(pd.DataFrame(rows), "y", "word")
    assert "p_vs_chance" not in plain and plain.k.tolist() == [6, 2]
    assert (plain.ci_level == 0.95).all()


def test_rates_by_sorts_levels_keeps_other_missing_columns_and_handles_no_rows():
    df = pd.DataFrame(
        {"word": ["cat", "bell", "cat", "apple", "bell"], "y": [1, 0, 0, 1, 1], "note": np.nan}
    )
    out = S.rates_by(df, "y", "word", chance=0.5)
    assert out.word.tolist() == ["apple", "bell", "cat"]  # sorted, not first-seen
    assert out.n.tolist() == [1, 2, 2] and out.k.tolist() == [1, 1, 1]
    empty = S.rates_by(df.assign(y=np.nan), "y", "word", chance=0.5)
    assert len(empty) == 0 and {"p_vs_chance", "p_holm"} <= set(empty.columns)
