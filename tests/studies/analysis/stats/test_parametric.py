"""Tests of ``studies.analysis.stats.parametric`` (moved from the suite on: studies.analysis
statistics: each function against the scipy/statsmodels call it names, and the paper's numbers
(shared/reference/studies.md) reproduced from the paper's summaries)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import stats
from statsmodels.stats.weightstats import ttost_paired

from studies.analysis import stats as S
from studies.analysis.paper import (
    paper_turing_frame,
)
from tests.helpers.study_analysis import (  # noqa: F401 (fixtures)
    close,
    fields,
    paired_frame,
    two_writer_answers,
)


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


# --------------------------------------------------------------------------- every argument


RATINGS = pd.DataFrame(
    {"confidence": [4, 5, 3, 4, 4, 5, 2, 4, 1, 2, "x"], "participant_id": list("aabbccddeef")}
)


@pytest.mark.parametrize(
    "alternative, null",
    [("greater", "mean <= 3"), ("less", "mean >= 3"), ("two-sided", "mean = 3")],
)
def test_one_sample_ttest_every_alternative_at_another_level(alternative, null):
    row = S.one_sample_ttest(RATINGS, "confidence", 3, alternative, alpha=0.2).iloc[0]
    x = np.array([4, 5, 3, 4, 4, 5, 2, 4, 1, 2], dtype=float)
    ref = stats.ttest_1samp(x, 3, alternative=alternative)
    ci = stats.ttest_1samp(x, 3).confidence_interval(0.8)
    close(
        fields(row, "statistic", "p_value", "estimate", "ci_low", "ci_high"),
        [ref.statistic, ref.pvalue, x.mean(), ci.low, ci.high],
    )
    assert (row.n, row.df, row.alpha, row.null_hypothesis) == (10, 9, 0.2, null)
    assert np.isnan(row.clusters) and row.ci_level == pytest.approx(0.8)
    assert row.test == "one-sample t-test vs 3 on ratings"
    assert row.method == f"scipy ttest_1samp ({alternative}); all rows independent"
    assert bool(row.reject) == (ref.pvalue < 0.2)


def test_one_sample_ttest_words_its_conclusion_by_alternative():
    high = pd.DataFrame({"confidence": [4, 5, 4, 5, 4, 5, 4, 5]})
    assert S.one_sample_ttest(high, popmean=3).iloc[0].conclusion.startswith("mean 4.50 > 3 (p = ")
    low = pd.DataFrame({"confidence": [1, 2, 1, 2, 1, 2, 1, 2]})
    assert S.one_sample_ttest(low, popmean=3).iloc[0].conclusion.startswith("mean 1.50 < 3 (p = ")
    near = pd.DataFrame({"confidence": [2, 4, 3, 3, 2, 4]})
    two = S.one_sample_ttest(near, popmean=3).iloc[0]
    assert two.conclusion == "not shown to differ from 3 (p = 1.000)"
    greater = S.one_sample_ttest(near, popmean=3, alternative="greater").iloc[0]
    assert greater.conclusion.startswith("not shown that mean > 3 (p = ")
    less = S.one_sample_ttest(near, popmean=3, alternative="less").iloc[0]
    assert less.conclusion.startswith("not shown that mean < 3 (p = ")


def test_one_sample_ttest_defaults_are_confidence_against_3_two_sided():
    df = pd.DataFrame({"confidence": [4, 5, 3, 4, 4, 5, 2, 4]})
    row = S.one_sample_ttest(df).iloc[0]
    ref = stats.ttest_1samp(df.confidence, 3.0)
    close(fields(row, "statistic", "p_value"), [ref.statistic, ref.pvalue])
    assert row.alpha == 0.05 and row.null_hypothesis == "mean = 3" and row.ci_level == 0.95


def test_one_sample_ttest_on_one_value_is_not_estimable_and_names_the_unit():
    one = S.one_sample_ttest(pd.DataFrame({"confidence": [4]})).iloc[0]
    assert one.conclusion == "not estimable: needs at least 2 values, got 1"
    assert one.estimate == 4 and one.n == 1 and one.method == "scipy ttest_1samp not run"
    assert one.null_hypothesis == "mean = 3" and one.alpha == 0.05
    none = S.one_sample_ttest(pd.DataFrame({"confidence": [np.nan]})).iloc[0]
    assert np.isnan(none.estimate) and none.n == 0
    same = S.one_sample_ttest(pd.DataFrame({"confidence": [4, 4]})).iloc[0]
    assert (
        same.conclusion == "not estimable: every rating is 4 (zero variance: no t-test or interval)"
    )
    by = S.one_sample_ttest(
        pd.DataFrame({"confidence": [4, 4, 4, 4], "word": list("aabb")}), cluster="word"
    ).iloc[0]
    assert by.conclusion.startswith("not estimable: every word mean is 4")
    assert by.test == "one-sample t-test vs 3 on word means" and by.clusters == 2


def _group_frame():
    rates = {"human": [0.9, 0.8, 0.7, 1.0, 0.6], "robot": [0.5, 0.7, 0.65, 0.8]}
    rows = []
    for writer, rs in rates.items():
        for i, r in enumerate(rs):
            k = round(r * 20)
            rows += [dict(writer=writer, word=f"w{i}", correct=float(j < k)) for j in range(20)]
    return pd.DataFrame(rows), np.array(rates["human"]), np.array(rates["robot"])


@pytest.mark.parametrize("equal_var", [True, False])
def test_group_ttest_matches_ttest_ind_and_its_interval(equal_var):
    df, human, robot = _group_frame()
    row = S.group_ttest(df, alpha=0.1, equal_var=equal_var).iloc[0]
    ref = stats.ttest_ind(robot, human, equal_var=equal_var)
    ci = ref.confidence_interval(0.9)
    close(
        fields(row, "estimate", "ci_low", "ci_high", "statistic", "p_value", "df"),
        [robot.mean() - human.mean(), ci.low, ci.high, ref.statistic, ref.pvalue, ref.df],
    )
    assert (row.n, row.alpha) == (9, 0.1) and row.ci_level == pytest.approx(0.9)
    assert row.test == "independent t-test on word rates (robot - human)"
    assert row.null_hypothesis == "robot rate = human rate"
    assert row.method == (
        f"scipy ttest_ind (equal_var={equal_var}) on 5+4 word rates; ignores pairing"
    )
    assert bool(row.reject) == (ref.pvalue < 0.1)
    if row.reject:
        assert row.conclusion.startswith("robot and human differ (p = ")
    else:
        assert row.conclusion.endswith("; this is not evidence of equality")


def test_group_ttest_conclusions_and_defaults():
    df, human, robot = _group_frame()
    row = S.group_ttest(df).iloc[0]
    ref = stats.ttest_ind(robot, human)
    close(row.p_value, ref.pvalue)
    assert row.alpha == 0.05 and row.ci_level == 0.95 and not row.reject
    assert (
        row.conclusion
        == f"difference not shown ({S.format_p(ref.pvalue)}); this is not evidence of equality"
    )
    far = df.assign(correct=np.where(df.writer == "robot", 0.0, df.correct))
    far.loc[far.index[(far.writer == "robot") & (far.word == "w0")][0], "correct"] = 1.0
    shown = S.group_ttest(far, levels=("human", "robot")).iloc[0]
    assert shown.reject and shown.conclusion.startswith("robot and human differ (p = ")
    swapped = S.group_ttest(df, levels=("robot", "human")).iloc[0]
    close(swapped.estimate, human.mean() - robot.mean())
    assert swapped.test == "independent t-test on word rates (human - robot)"


def test_group_ttest_not_estimable_cases_name_why():
    df, _, _ = _group_frame()
    one_word = df[(df.writer == "human") | (df.word == "w0")]
    row = S.group_ttest(one_word).iloc[0]
    assert row.conclusion == "not estimable: needs at least 2 words for each of human, robot"
    assert row.alpha == 0.05
    missing = S.group_ttest(df[df.writer == "human"]).iloc[0]
    assert missing.conclusion == "not estimable: needs at least 2 words for each of human, robot"
    flat = df.assign(correct=np.where(df.writer == "robot", 1.0, 0.0))
    row = S.group_ttest(flat).iloc[0]
    assert row.conclusion == (
        "not estimable: every human word rate is 0 and every robot word rate is 1 "
        "(zero variance: no t-test or interval)"
    )
    assert (row.estimate, row.n, row.null_hypothesis) == (1.0, 9, "robot rate = human rate")
    assert row.method == "scipy ttest_ind not run"
    one_flat = df.assign(correct=np.where(df.writer == "robot", 1.0, df.correct))
    assert np.isfinite(S.group_ttest(one_flat).iloc[0].p_value)  # one group spread is enough


def test_paired_tests_at_another_level_margin_and_by_word(paired_frame):
    out = S.paired_tests(paired_frame, cluster="word", margin=0.2, alpha=0.1)
    wide = paired_frame.pivot_table(index="word", columns="writer", values="correct")
    r, h = wide["robot"].to_numpy(), wide["human"].to_numpy()
    d = r - h
    ref = stats.ttest_rel(r, h)
    ci90, ci80 = ref.confidence_interval(0.9), ref.confidence_interval(0.8)
    close(fields(out.iloc[0], "ci_low", "ci_high", "p_value"), [ci90.low, ci90.high, ref.pvalue])
    p = ttost_paired(r, h, -0.2, 0.2)[0]
    close(fields(out.iloc[1], "ci_low", "ci_high", "p_value"), [ci80.low, ci80.high, p])
    ni = stats.ttest_1samp(d, -0.2, alternative="greater")
    close(
        fields(out.iloc[2], "ci_low", "p_value", "statistic"), [ci80.low, ni.pvalue, ni.statistic]
    )
    close(out.ci_level, [0.9, 0.8, 0.9])
    assert list(out.test) == [
        "paired t-test by word (robot - human)",
        "paired TOST by word (±0.2)",
        "non-inferiority by word (margin 0.2)",
    ]
    assert list(out.null_hypothesis) == [
        "robot - human = 0",
        "robot - human <= -0.2 or >= 0.2",
        "robot - human <= -0.2",
    ]
    assert (out.alpha == 0.1).all() and (out.clusters == 10).all()
    assert out.method.tolist() == [
        "scipy ttest_rel; 10 words with both levels",
        "statsmodels ttost_paired; 10 words with both levels",
        "scipy ttest_1samp (greater) on paired differences; 10 words with both levels",
    ]


def test_paired_tests_words_each_conclusion(paired_frame):
    out = S.paired_tests(paired_frame)
    d_mean = out.iloc[0].estimate
    direction = "higher" if d_mean > 0 else "lower"
    first = out.iloc[0]
    if first.reject:
        assert first.conclusion.startswith(f"robot {direction} than human (p = ")
    else:
        assert first.conclusion.endswith("; not evidence of equality")
    ni = out.iloc[2]
    want = (
        "non-inferior: robot no worse than human by 0.1 or more"
        if ni.reject
        else "non-inferiority not shown"
    )
    assert ni.conclusion.startswith(want + " (p = ")
    answers = two_writer_answers(12, 10, human=0.9, robot=0.2, seed=0)
    lower = S.paired_tests(answers).iloc[0]
    assert lower.reject and lower.conclusion.startswith("robot lower than human (p = ")
    higher = S.paired_tests(answers, levels=("robot", "human")).iloc[0]
    assert higher.conclusion.startswith("human higher than robot (p = ")


def test_paired_tests_not_estimable_cases_name_why(paired_frame):
    no_robot = S.paired_tests(paired_frame[paired_frame.writer == "human"]).iloc[0]
    assert no_robot.conclusion == "not estimable: no robot rows" and no_robot.alpha == 0.05
    two = paired_frame[paired_frame.participant_id.isin(["P0", "P1"])]
    row = S.paired_tests(two).iloc[0]
    assert row.conclusion == "not estimable: fewer than 3 pairs" and row.n == 2
    assert row.null_hypothesis == "robot - human = 0"
    assert row.method == "2 participants with both levels"
    same = pd.DataFrame(
        [
            dict(participant_id=p, writer=w, correct=float(w == "robot"))
            for p in range(4)
            for w in ("human", "robot")
        ]
    )
    row = S.paired_tests(same).iloc[0]
    assert row.conclusion == (
        "not estimable: every participant's paired difference is 1 (zero variance: no t-test or interval)"
    )
    assert row.estimate == 1.0 and row.n == 4 and row.clusters == 4
    empty = S.paired_tests(paired_frame.assign(correct=np.nan)).iloc[0]
    assert empty.conclusion == "not estimable: no human rows"


def test_group_ttest_with_two_words_per_writer_is_a_test():
    df, _, _ = _group_frame()
    two = df[df.word.isin(["w0", "w1"])]
    row = S.group_ttest(two).iloc[0]
    rates = two.groupby(["writer", "word"])["correct"].mean()
    ref = stats.ttest_ind(rates["robot"], rates["human"])
    close(row.p_value, ref.pvalue)
    assert row.n == 4


def test_paired_tests_with_three_pairs_is_a_test_and_named_when_not():
    rows = [
        dict(participant_id=p, writer=w, correct=c)
        for p, (h, r) in enumerate([(1.0, 0.0), (1.0, 1.0), (0.0, 0.0)])
        for w, c in (("human", h), ("robot", r))
    ]
    three = S.paired_tests(pd.DataFrame(rows))
    d = np.array([-1.0, 0.0, 0.0])
    close(three.p_value.iloc[0], stats.ttest_1samp(d, 0).pvalue)
    assert three.n.iloc[0] == 3
    two = S.paired_tests(pd.DataFrame(rows[:4])).iloc[0]
    assert two.test == "paired t-test by participant (robot - human)"
    missing = S.paired_tests(pd.DataFrame(rows[:4]).query("writer == 'human'")).iloc[0]
    assert missing.test == "paired t-test by participant (robot - human)"


def test_paired_tests_without_complete_pairs_warn_nothing():
    import warnings

    rows = [dict(participant_id=p, writer=("human", "robot")[p % 2], correct=1.0) for p in range(6)]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        row = S.paired_tests(pd.DataFrame(rows)).iloc[0]
    assert (
        row.n == 0
        and np.isnan(row.estimate)
        and row.conclusion == "not estimable: fewer than 3 pairs"
    )
    assert row.method == "0 participants with both levels (6 dropped: one level only)"


def test_paired_tests_ignore_other_conditions_and_unused_categories(paired_frame):
    other = paired_frame[paired_frame.participant_id.isin(["P0", "P1"])].assign(writer="other")
    df = pd.concat([paired_frame, other], ignore_index=True)
    categories = [*sorted(df.participant_id.unique()), "P-unused"]
    df["participant_id"] = pd.Categorical(df.participant_id, categories=categories)
    df["writer"] = pd.Categorical(df.writer, categories=["human", "robot", "other", "unused"])
    out = S.paired_tests(df)
    plain = S.paired_tests(paired_frame)
    close(out.p_value, plain.p_value)
    assert (
        out.n.iloc[0] == 20
        and out.method.iloc[0] == "scipy ttest_rel; 20 participants with both levels"
    )


def test_group_ttest_zero_variance_row_names_the_test_and_the_difference():
    df, _, _ = _group_frame()
    halves = df.assign(correct=np.where(df.writer == "robot", 1.0, (df.index % 2).astype(float)))
    row = S.group_ttest(halves, alpha=0.1).iloc[0]
    assert row.test == "independent t-test on word rates (robot - human)"
    assert row.estimate == 0.5 and row.alpha == 0.1
    assert row.conclusion.startswith("not estimable: every human word rate is 0.5")
    short = S.group_ttest(df[df.writer == "human"], alpha=0.1).iloc[0]
    assert short.test == "independent t-test on word rates (robot - human)" and short.alpha == 0.1


def test_group_ttest_with_one_constant_group_warns_nothing():
    import warnings

    df, _, _ = _group_frame()
    one_flat = df.assign(correct=np.where(df.writer == "robot", 1.0, df.correct))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        row = S.group_ttest(one_flat).iloc[0]
    assert np.isfinite(row.p_value)
