"""Tests of ``studies.analysis.participants`` (moved from the suite on: simulated participants with
known truth: the simulator honours the truth it is given, and the analysis reaches the right
conclusions from its responses)."""

from __future__ import annotations

import numpy as np
import pytest

from studies.analysis.analyze import analyze_table
from studies.analysis.config import AnalysisSettings
from studies.analysis.participants import (
    confidence_shift,
    simulate_readability,
    simulate_turing,
)

CFG = AnalysisSettings(margin=0.05, margin_source="preregistered", mixed_model=False)


CFG2 = AnalysisSettings(margin=0.10, margin_source="preregistered", mixed_model=False)


def test_confidence_shift_gives_the_stated_mean_rating():
    from scipy import stats

    shift = confidence_shift(3.4)
    assert 1 + stats.norm.cdf(
        (shift - np.array([1.5, 2.5, 3.5, 4.5])) / 1.5
    ).sum() == pytest.approx(3.4)


def test_robot_indistinguishable_equivalence_to_chance_is_shown_with_enough_participants():
    table, _ = simulate_turing(300, 0.2, icc=0.05, seed=2)
    v = analyze_table(table, CFG).studies[0].verdict
    assert v["h1"] == "equivalent to chance" and v["h1_equivalent"] and not v["above_chance"]


def test_robot_indistinguishable_but_too_few_participants_is_undecided_not_equivalent():
    table, _ = simulate_turing(20, 0.2, icc=0.1, seed=3)
    v = analyze_table(table, CFG).studies[0].verdict
    assert v["h1"] == "inconclusive" and not v["h1_equivalent"]


def test_robot_detectable_superiority_over_chance_is_shown():
    table, _ = simulate_turing(50, 0.45, icc=0.1, seed=4)
    st = analyze_table(table, CFG).studies[0]
    assert st.verdict["h1"] == "above chance" and st.verdict["rate_ci"][0] > 0.2
    assert st.conclusions[0].startswith("**H1 not supported**")


def test_h2_confident_participants_are_above_neutral():
    table, _ = simulate_turing(50, 0.45, confidence_mean=3.6, seed=5)
    assert analyze_table(table, CFG).studies[0].verdict["h2"] == "above neutral"


def test_h2_clustered_ratings_fool_the_independent_test_but_not_participant_means():
    table, _ = simulate_turing(50, 0.3, confidence_mean=3.0, confidence_icc=0.5, seed=8)
    st = analyze_table(table, CFG).studies[0]
    flat = st.tests[st.tests.test == "one-sample t-test vs 3 on ratings"].iloc[0]
    means = st.tests[st.tests.test == "one-sample t-test vs 3 on participant means"].iloc[0]
    assert means.ci_low < 3 < means.ci_high and st.verdict["h2"] == "not different from neutral"
    assert (flat.ci_high - flat.ci_low) < 0.6 * (
        means.ci_high - means.ci_low
    )  # independence: too narrow


def test_inattentive_participants_are_excluded_and_named():
    table, _ = simulate_turing(60, 0.45, icc=0.1, inattentive=15, seed=6)
    an = analyze_table(table, CFG)
    st = an.studies[0]
    assert st.data["participant_id"].nunique() == 60
    assert any("15 participants failed an attention check and were excluded" in n for n in an.notes)
    assert st.verdict["h1"] == "above chance"


def test_readability_equal_writers_are_shown_equally_readable():
    table, _ = simulate_readability(120, 0.8, icc=0.1, seed=7)
    v = analyze_table(table, CFG2).studies[0].verdict
    assert v["verdict"] == "equally readable" and v["equivalent"] and v["noninferior"]


def test_readability_worse_robot_is_less_readable_and_not_noninferior():
    table, _ = simulate_readability(60, 0.6, human_rate=0.85, icc=0.1, seed=9)
    v = analyze_table(table, CFG2).studies[0].verdict
    assert v["verdict"] == "robot less readable" and not v["noninferior"] and v["difference"] < -0.1


def test_readability_paper_sized_study_with_equal_writers_is_not_called_equal():
    table, _ = simulate_readability(30, 0.8, icc=0.1, seed=10)
    st = analyze_table(table, CFG2).studies[0]
    paper = st.tests[st.tests.approach == "paper-faithful"].iloc[0]
    assert not paper.reject and "not evidence of equality" in paper.conclusion
    assert st.verdict["verdict"] in {"non-inferior", "inconclusive", "equally readable"}
    assert "paired by participant" in st.conclusions[0]


def test_readability_between_participants_falls_back_on_the_gee():
    table, _ = simulate_readability(300, 0.8, seed=12)
    between = table[
        ((table.list_id == "A") & (table.writer == "human"))
        | ((table.list_id == "B") & (table.writer == "robot"))
        | (table.is_attention_check == "true")
    ]
    st = analyze_table(between, CFG2).studies[0]
    assert st.verdict["primary"] == "GEE difference (robot - human)"
    assert (
        st.verdict["verdict"] == "equally readable" and "GEE on participants" in st.conclusions[0]
    )
