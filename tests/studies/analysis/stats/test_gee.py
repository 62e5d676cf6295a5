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
from tests.helpers.study_analysis import (  # noqa: F401 (fixtures)
    binary_frame,
    close,
    fields,
    gee_difference_reference,
    paired_frame,
    two_writer_answers,
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
    ref = gee_difference_reference(paired_frame, "robot")
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


# --------------------------------------------------------------------------- every argument


def _rate_reference(df, outcome, cluster, chance):
    y = df[outcome].to_numpy(dtype=float)
    groups = pd.factorize(df[cluster])[0]
    off = np.log(chance / (1 - chance))
    ref = sm.GEE(
        y,
        np.ones((len(y), 1)),
        groups=groups,
        family=sm.families.Binomial(),
        cov_struct=sm.cov_struct.Exchangeable(),
        offset=np.full(len(y), off),
    ).fit(cov_type="bias_reduced")
    return float(ref.params[0]), float(ref.bse[0]), off, ref


def _expit(x):
    return 1 / (1 + np.exp(-x))


def test_gee_rate_matches_statsmodels_gee_with_the_chance_offset_and_a_hand_tost():
    df = binary_frame(150, 600, 30)
    rows = S.gee_rate(df, "y", "participant_id", 0.3, margin=0.04, alpha=0.1)
    b, se, off, ref = _rate_reference(df, "y", "participant_id", 0.3)
    q, q2 = stats.norm.ppf(0.95), stats.norm.ppf(0.9)
    close(
        fields(rows.iloc[0], "estimate", "ci_low", "ci_high", "statistic", "p_value"),
        [
            _expit(off + b),
            _expit(off + b - q * se),
            _expit(off + b + q * se),
            b / se,
            ref.pvalues[0],
        ],
        1e-7,
    )
    lo_b = np.log(0.26 / 0.74) - off
    up_b = np.log(0.34 / 0.66) - off
    p_low, p_upp = stats.norm.sf((b - lo_b) / se), stats.norm.cdf((b - up_b) / se)
    close(
        fields(rows.iloc[1], "estimate", "ci_low", "ci_high", "p_value", "p_lower", "p_upper"),
        [
            _expit(off + b),
            _expit(off + b - q2 * se),
            _expit(off + b + q2 * se),
            max(p_low, p_upp),
            p_low,
            p_upp,
        ],
        1e-7,
    )
    close(rows.ci_level, [0.9, 0.8])
    assert rows.test.tolist() == ["GEE rate vs chance", "GEE TOST vs chance"]
    assert rows.null_hypothesis.tolist() == ["rate = 0.3", "rate <= 0.26 or rate >= 0.34"]
    assert (rows.n == 600).all() and (rows.clusters == 30).all() and (rows.alpha == 0.1).all()
    rho = ref.model.cov_struct.dep_params
    assert rows.method.iloc[0] == (
        f"GEE logit, exchangeable (working ICC {rho:.3f}), bias-reduced robust SE, 30 clusters"
    )
    assert rows.conclusion.iloc[0].startswith("below chance (p = ")  # 0.25 < 0.3, 600 answers


def test_gee_rate_defaults_side_and_cluster_count_note():
    rng = np.random.default_rng(2)
    df = pd.DataFrame(
        {
            "participant_id": np.repeat(np.arange(25), 8),
            "chose_robot": (rng.random(200) < 0.4).astype(float),
        }
    )
    rows = S.gee_rate(df)
    assert len(rows) == 1 and rows.alpha.iloc[0] == 0.05 and rows.ci_level.iloc[0] == 0.95
    *_, ref = _rate_reference(df, "chose_robot", "participant_id", 0.2)
    close(rows.p_value, [ref.pvalues[0]], 1e-7)
    assert rows.conclusion.iloc[0].startswith("above chance (p = ")
    assert "fewer than 20 clusters" not in rows.method.iloc[0]  # 25 clusters
    near = df.assign(chose_robot=(np.arange(200) % 5 == 0).astype(float))
    row = S.gee_rate(near).iloc[0]
    assert row.conclusion.startswith("not shown to differ from chance (p = ")
    few = S.gee_rate(df[df.participant_id < 19]).iloc[0]
    assert few.method.endswith("; fewer than 20 clusters: the robust SE is unreliable")
    by_word = S.gee_rate(df.assign(word=np.tile(np.arange(8), 25)), cluster="word").iloc[0]
    assert by_word.clusters == 8


def test_gee_rate_not_estimable_rows_say_why_for_each_test():
    rows = S.gee_rate(binary_frame(100, 100), "y", "participant_id", 0.2, margin=0.05, alpha=0.1)
    assert rows.test.tolist() == ["GEE rate vs chance", "GEE TOST vs chance"]
    assert (rows.conclusion == "not estimable: every answer is 1: the log-odds are infinite").all()
    assert (rows.n == 100).all() and (rows.clusters == 10).all() and (rows.alpha == 0.1).all()
    one = S.gee_rate(binary_frame(6, 10, participants=10), "y", cluster="word").iloc[0]
    assert one.conclusion == "not estimable: needs answers from at least 2 words"
    empty = S.gee_rate(pd.DataFrame({"participant_id": [0], "chose_robot": [np.nan]})).iloc[0]
    assert empty.n == 0 and empty.clusters == 0 and empty.conclusion.startswith("not estimable")


def test_gee_difference_at_another_level_with_swapped_levels_and_extra_conditions(paired_frame):
    extra = paired_frame.iloc[:30].assign(writer="other")
    df = pd.concat([paired_frame, extra])
    rows = S.gee_difference(df, levels=("robot", "human"), margin=0.15, alpha=0.1)
    ref = gee_difference_reference(paired_frame, "human")
    d, se = ref.params.iloc[1], ref.bse.iloc[1]
    q, q2 = stats.norm.ppf(0.95), stats.norm.ppf(0.9)
    close(fields(rows.iloc[0], "estimate", "ci_low", "ci_high"), [d, d - q * se, d + q * se], 1e-7)
    p1, p2 = stats.norm.sf((d + 0.15) / se), stats.norm.cdf((d - 0.15) / se)
    close(fields(rows.iloc[1], "p_lower", "p_upper", "ci_low"), [p1, p2, d - q2 * se], 1e-7)
    close(rows.ci_level, [0.9, 0.8, 0.9])
    assert rows.null_hypothesis.tolist() == [
        "human - robot = 0",
        "human - robot <= -0.15 or >= 0.15",
        "human - robot <= -0.15",
    ]
    assert (rows.n == 200).all() and (rows.clusters == 20).all() and (rows.alpha == 0.1).all()
    rho = ref.model.cov_struct.dep_params
    assert rows.method.iloc[0] == (
        f"GEE identity link, exchangeable (working ICC {rho:.3f}), bias-reduced robust SE"
    )
    direction = "higher" if d > 0 else "lower"
    if rows.reject.iloc[0]:
        assert rows.conclusion.iloc[0].startswith(f"human {direction} than robot (p = ")
    else:
        assert rows.conclusion.iloc[0].startswith("difference not shown (p = ")
    ni = rows.iloc[2]
    assert ni.conclusion.startswith(
        "non-inferior (p = " if ni.reject else "non-inferiority not shown"
    )
    assert len(S.gee_difference(paired_frame)) == 1  # no margin: one row


def test_gee_difference_words_a_clear_difference():
    answers = two_writer_answers(24, 6, human=0.9, robot=0.3, seed=5)
    row = S.gee_difference(answers).iloc[0]
    assert row.reject and row.conclusion.startswith("robot lower than human (p = ")
    row = S.gee_difference(answers, levels=("robot", "human")).iloc[0]
    assert row.conclusion.startswith("human higher than robot (p = ")


def test_gee_difference_not_estimable_and_fixed_level_cases(paired_frame):
    one = S.gee_difference(paired_frame[paired_frame.participant_id == "P0"]).iloc[0]
    assert one.conclusion == "not estimable: needs answers from at least 2 participants"
    assert one.test == "GEE difference (robot - human)" and one.clusters == 1
    human = S.gee_difference(paired_frame[paired_frame.writer == "human"]).iloc[0]
    assert human.conclusion == "not estimable: only one writer level present"
    ones = S.gee_difference(paired_frame.assign(correct=1.0)).iloc[0]
    assert ones.conclusion == "not estimable: every answer is 1 (no variation: the robust SE is 0)"
    assert ones.estimate == 0.0
    split = paired_frame.assign(correct=(paired_frame.writer == "robot").astype(float))
    row = S.gee_difference(split).iloc[0]
    assert row.conclusion == (
        "not estimable: every robot answer is 1 and every human answer is 0 "
        "(perfect separation: the robust SE is 0)"
    )
    assert row.estimate == 1.0
    half = paired_frame.assign(
        correct=np.where(paired_frame.writer == "robot", 1.0, paired_frame.correct)
    )
    row = S.gee_difference(half).iloc[0]
    assert np.isfinite(row.p_value)
    assert row.method.endswith(
        "; every robot answer is 1: the robust SE takes that rate as known exactly "
        "(interval too narrow; prefer the paired tests)"
    )


def test_gee_fit_falls_back_to_the_robust_sandwich_where_bias_reduction_fails():
    from studies.analysis.stats.gee import _gee_fit

    # one cluster holds every x = 1 answer: its block of (I - H) is singular (statsmodels
    # raises LinAlgError in the Mancl-DeRouen correction), the plain sandwich still exists
    y = np.array([1.0, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0])
    x = np.array([1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    groups = np.array([0, 0, 1, 1, 1, 1, 1])
    exog = np.column_stack([np.ones(7), x])
    with pytest.raises(np.linalg.LinAlgError):
        sm.GEE(
            y,
            exog,
            groups=groups,
            family=sm.families.Gaussian(),
            cov_struct=sm.cov_struct.Exchangeable(),
        ).fit(cov_type="bias_reduced")
    res, cov, rho, notes = _gee_fit(y, exog, groups, sm.families.Gaussian())
    assert cov == "robust" and np.isfinite(res.params).all()
    assert notes == ["fewer than 20 clusters: the robust SE is unreliable"]
    assert rho == float(np.atleast_1d(res.model.cov_struct.dep_params)[0])


def test_a_failed_fit_message_is_one_line_of_at_most_200_characters():
    from studies.analysis.stats.gee import _message

    assert _message(ValueError("a\n  b\tc")) == "a b c"
    assert _message(ValueError("x" * 300)) == "x" * 200


def test_gee_difference_keeps_rows_with_gaps_elsewhere_and_counts_clusters(paired_frame):
    gappy = paired_frame.assign(note=np.where(np.arange(len(paired_frame)) % 3 == 0, np.nan, 1.0))
    row = S.gee_difference(gappy).iloc[0]
    assert row.n == 200 and row.clusters == 20
    close(row.estimate, S.gee_difference(paired_frame).iloc[0].estimate)
    empty = S.gee_difference(paired_frame.assign(correct=np.nan)).iloc[0]
    assert empty.n == 0 and empty.clusters == 0
    assert empty.conclusion == "not estimable: needs answers from at least 2 participants"


def test_gee_difference_with_two_clusters_is_a_test():
    rows = [
        dict(participant_id=p, writer=w, correct=c)
        for p in ("a", "b")
        for w, cs in (("human", (1, 0, 1, 1)), ("robot", (0, 0, 1, 0)))
        for c in cs
    ]
    row = S.gee_difference(pd.DataFrame(rows)).iloc[0]
    assert row.clusters == 2 and not row.conclusion.startswith("not estimable")
    assert "fewer than 20 clusters" in row.method


def test_gee_difference_with_a_single_answer_of_one_level_notes_it():
    rng = np.random.default_rng(3)
    rows = [
        dict(participant_id=p, writer="human", correct=float(rng.random() < 0.6))
        for p in range(10)
        for _ in range(4)
    ]
    rows.append(dict(participant_id=0, writer="robot", correct=1.0))
    row = S.gee_difference(pd.DataFrame(rows)).iloc[0]
    assert "every robot answer is 1: the robust SE takes that rate as known exactly" in row.method


# --------------------------------------------------------------------------- every field, every edge


def _stopped_early(monkeypatch):
    """GEE's real fit stopped after one iteration short of its (unreachable) tolerance:
    statsmodels warns "Iteration limit reached prior to convergence", as it does for a fit that
    does not converge."""
    fit = sm.GEE.fit
    monkeypatch.setattr(sm.GEE, "fit", lambda self, **kw: fit(self, maxiter=1, ctol=1e-300, **kw))


def test_gee_rate_says_when_the_fit_did_not_converge_beside_its_other_notes(monkeypatch):
    _stopped_early(monkeypatch)
    row = S.gee_rate(binary_frame(30, 100, participants=10), "y").iloc[0]
    assert row.method.endswith(
        " SE, 10 clusters; GEE did not fully converge; "
        "fewer than 20 clusters: the robust SE is unreliable"
    )


def test_gee_other_warnings_add_no_convergence_note(monkeypatch):
    import warnings

    fit = sm.GEE.fit

    def noisy(self, **kw):
        warnings.warn("divide by zero encountered", RuntimeWarning, stacklevel=2)
        return fit(self, **kw)

    monkeypatch.setattr(sm.GEE, "fit", noisy)
    row = S.gee_rate(binary_frame(60, 250, participants=25), "y").iloc[0]
    assert "converge" not in row.method


def test_gee_rate_with_two_clusters_is_fitted():
    df = pd.DataFrame(
        {"participant_id": [0] * 6 + [1] * 6, "y": [1, 0, 0, 1, 0, 0, 1, 1, 0, 0, 0, 1]}
    )
    rows = S.gee_rate(df, "y", margin=0.05)
    assert rows.clusters.tolist() == [2, 2] and rows.p_value.notna().all()


def test_gee_rate_not_estimable_without_margin_is_one_row():
    rows = S.gee_rate(binary_frame(0, 100), "y")
    assert rows.test.tolist() == ["GEE rate vs chance"]


def test_gee_tost_and_non_inferiority_rows_carry_the_statistic_method_and_wording(paired_frame):
    rows = S.gee_difference(paired_frame, margin=0.1)
    ref = gee_difference_reference(paired_frame, "robot")
    d, se = ref.params.iloc[1], ref.bse.iloc[1]
    close(rows.statistic, [d / se, d / se, (d + 0.1) / se], 1e-7)
    assert rows.method.iloc[0].startswith("GEE identity link")
    assert rows.method.tolist() == [rows.method.iloc[0]] * 3  # every row names the fit
    tost = rows.iloc[1]
    p1, p2 = stats.norm.sf((d + 0.1) / se), stats.norm.cdf((d - 0.1) / se)
    if max(p1, p2) < 0.05:
        want = "equivalent: difference within (-0.1, 0.1) (p = "
    else:
        want = "equivalence not shown: null '"
        want += "difference <= -0.1'" if p1 >= 0.05 else "difference >= 0.1'"
    assert tost.conclusion.startswith(want), tost.conclusion

    rate = S.gee_rate(binary_frame(120, 600, 30), "y", margin=0.05)
    close(rate.statistic, [rate.statistic.iloc[0]] * 2)
    assert np.isfinite(rate.statistic.iloc[1])
    assert rate.method.iloc[0].startswith("GEE logit")
    assert rate.method.tolist() == [rate.method.iloc[0]] * 2
    assert rate.conclusion.iloc[1].startswith("equivalent: rate within (0.15, 0.25) (p = ")
