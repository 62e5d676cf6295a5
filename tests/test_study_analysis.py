"""studies.analysis statistics: each function against the scipy/statsmodels call it names, and the
paper's numbers (shared/reference/studies.md) reproduced from the paper's summaries."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import statsmodels.api as sm
from numpy.testing import assert_allclose
from scipy import stats
from statsmodels.stats.multitest import multipletests
from statsmodels.stats.proportion import binom_tost, proportion_confint
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


def binary_frame(k: int, n: int, participants: int = 10) -> pd.DataFrame:
    y = np.r_[np.ones(k), np.zeros(n - k)]
    rng = np.random.default_rng(0)
    rng.shuffle(y)
    return pd.DataFrame(
        {
            "participant_id": np.arange(n) % participants,
            "word": np.arange(n) // participants,
            "y": y,
        }
    )


def close(got, want, rel: float = 1e-9) -> None:
    """``got`` equals ``want`` to a relative tolerance and no absolute one: a p value of 1e-30
    must match 1e-30, not anything below pytest.approx's default absolute 1e-12."""
    assert_allclose(np.asarray(got, dtype=float), np.asarray(want, dtype=float), rtol=rel, atol=0)


def fields(row: pd.Series, *names: str) -> list[float]:
    return [float(row[n]) for n in names]


@pytest.fixture(scope="module")
def paired_frame() -> pd.DataFrame:
    """20 participants x 10 trials, half per writer, participant effects shared by both writers."""
    rng = np.random.default_rng(4)
    rows = []
    for p in range(20):
        u = rng.normal(0, 0.8)
        for w in range(10):
            writer = "human" if (w < 5) == (p % 2 == 0) else "robot"
            base = 1.2 if writer == "human" else 1.0
            rows.append(
                dict(
                    participant_id=f"P{p}",
                    word=f"w{w}",
                    writer=writer,
                    correct=float(rng.random() < 1 / (1 + np.exp(-(base + u)))),
                )
            )
    return pd.DataFrame(rows)


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


def test_icc_oneway_matches_the_anova_formula():
    df = pd.DataFrame({"g": np.repeat([0, 1, 2], 3), "v": [1, 2, 3, 4, 5, 6, 8, 9, 7]})
    out = S.icc_oneway(df, "v", "g").iloc[0]
    msb = 3 * ((2 - 5) ** 2 + (5 - 5) ** 2 + (8 - 5) ** 2) / 2
    msw = 6 / 6
    assert out.icc == pytest.approx((msb - msw) / (msb + 2 * msw))
    assert out.design_effect == pytest.approx(1 + 2 * out.icc)


def test_mixed_logit_recovers_a_crossed_model_and_reports_its_caveat():
    rng = np.random.default_rng(1)
    p, w = np.repeat(np.arange(60), 10), np.tile(np.arange(10), 60)
    eta = -0.5 + rng.normal(0, 0.7, 60)[p] + rng.normal(0, 0.3, 10)[w]
    df = pd.DataFrame(
        {
            "participant_id": p,
            "word": w,
            "y": (rng.random(600) < 1 / (1 + np.exp(-eta))).astype(float),
        }
    )
    out = S.mixed_logit(df, "y").set_index("term")
    assert out.loc["Intercept", "ci_low"] < -0.5 < out.loc["Intercept", "ci_high"]
    assert 0.4 < out.loc["sd(participant_id)", "post_mean"] < 1.1
    assert out["status"].str.startswith("ok (variational Bayes").all()


def test_mixed_logit_failure_is_a_row_not_an_exception(monkeypatch):
    from statsmodels.genmod.bayes_mixed_glm import BinomialBayesMixedGLM

    def boom(self, *a, **k):
        raise np.linalg.LinAlgError("singular matrix")

    monkeypatch.setattr(BinomialBayesMixedGLM, "fit_vb", boom)
    out = S.mixed_logit(paper_turing_frame(), "chose_robot")
    assert len(out) == 1 and out.status.iloc[0] == "failed: LinAlgError: singular matrix"
    same = S.mixed_logit(binary_frame(0, 100), "y")
    assert same.status.iloc[0].startswith("failed: every answer is 0")


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


def test_statistics_name_a_missing_column():
    with pytest.raises(KeyError, match="column 'chose' not in the frame"):
        S.binomial_test(paper_turing_frame(), "chose")


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


def test_a_study_where_almost_every_word_was_spotted_by_everyone_analyses(tmp_path):
    """Simulated at a 0.999 rate, 9 of 10 words reach 100 %: the report is written, exit 0
    (the per-word figure used to fail on a negative error bar)."""
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    study = str(root / "conf/study/turing.yaml")
    responses = tmp_path / "turing.csv"

    def run(*args: str) -> subprocess.CompletedProcess:
        code = "import sys; from studies.cli import main; sys.exit(main())"
        return subprocess.run(
            [sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=300
        )

    made = run(
        "simulate",
        "turing",
        "--participants",
        "20",
        "--true-rate",
        "0.999",
        "--icc",
        "0",
        "--seed",
        "1",
        "--study",
        study,
        "--out",
        str(responses),
    )
    assert made.returncode == 0, made.stderr
    rates = pd.read_csv(responses).groupby("word")["chose_robot"].mean()
    assert (rates == 1.0).sum() >= 5  # boundary words are really there
    result = run("analyze", str(responses), "--study", study, "--out", str(tmp_path / "report"))
    assert result.returncode == 0, result.stderr[-2000:]
    assert (tmp_path / "report" / "report.html").is_file()
