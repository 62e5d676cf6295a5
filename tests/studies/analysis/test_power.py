"""The sample-size planner reproduces the planning figures in shared/reference/studies.md and agrees
with statsmodels and with Monte Carlo."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats
from statsmodels.stats.power import TTestPower
from statsmodels.stats.proportion import power_binom_tost

from studies.analysis import power as P


def test_exact_tost_power_matches_statsmodels_power_binom_tost():
    ns = np.array([20, 57, 100, 333, 500, 561, 570, 1000])
    for rate in (0.17, 0.2, 0.22):
        ours = P.binomial_tost_power(ns, rate, 0.2, 0.05)
        ref = [max(power_binom_tost(0.15, 0.25, int(n), p_alt=rate), 0.0) for n in ns]
        np.testing.assert_allclose(ours, ref, rtol=1e-12, atol=0)


def test_the_papers_500_trials_have_power_073():
    assert P.binomial_tost_power(500, 0.2, 0.2, 0.05) == pytest.approx(0.73, abs=0.005)


@pytest.mark.parametrize(
    ("rate", "power", "trials"), [(0.20, 0.8, 570), (0.20, 0.9, 714), (0.22, 0.8, 1301)]
)
def test_trials_for_equivalence_to_chance_match_studies_md(rate, power, trials):
    need = P.binomial_tost_sample_size(rate, 0.2, 0.05, 0.05, power)
    assert need.stable == trials
    ns = np.arange(need.stable, need.stable + 400)
    assert (P.binomial_tost_power(ns, rate, 0.2, 0.05) >= power).all()  # stays above from there on
    assert P.binomial_tost_power(need.stable - 1, rate, 0.2, 0.05) < power
    assert need.first <= need.stable


def test_a_rate_outside_the_margin_has_no_sample_size():
    assert P.binomial_tost_sample_size(0.3, 0.2, 0.05) == P.TrialsNeeded(None, None)


def test_clustered_plan_is_about_150_by_10_or_100_by_20():
    plan = P.turing_plan(rates=[0.2], powers=[0.8], words=[10, 20]).set_index("words")
    assert plan.loc[10, "participants"] == pytest.approx(150, abs=5)
    assert plan.loc[20, "participants"] == pytest.approx(100, abs=5)
    assert (plan["trials"] == 570).all()


def test_participants_needed_reduces_to_trials_over_words_without_clustering_and_caps_with_few_words():
    assert P.participants_needed(570, 10, icc=0.0, word_icc=0.0) == pytest.approx(57)
    assert (
        P.participants_needed(570, 10, icc=0.0, word_icc=0.02) == np.inf
    )  # 10 words cannot get there


def test_paired_tost_for_study_2_needs_about_53_participants():
    plan = P.readability_plan(rates=[0.8], differences=[0.0], powers=[0.8])
    tost = plan[plan.test == "paired TOST"].iloc[0]
    assert tost.participants == pytest.approx(53, abs=3)
    independent = P.readability_plan(
        rates=[0.8], differences=[0.0], powers=[0.8], icc=0, word_icc=0
    )
    assert independent[independent.test == "paired TOST"].iloc[0].participants == pytest.approx(
        53, abs=4
    )


def test_paired_difference_sd_without_clustering_is_the_binomial_sd():
    assert P.paired_difference_sd(0.8, 0.8, 5, 0.0, 0.0) == pytest.approx(np.sqrt(2 * 0.16 / 5))
    assert P.paired_difference_sd(0.8, 0.8, 5, 0.2, 0.0) < np.sqrt(
        2 * 0.16 / 5
    )  # shared effect cancels


def test_paired_tost_power_matches_a_monte_carlo_of_ttost_paired():
    rng = np.random.default_rng(0)
    n, sd, reps = 30, 0.25, 4000
    d = rng.normal(0.02, sd, (reps, n))
    m, se = d.mean(1), d.std(1, ddof=1) / np.sqrt(n)
    tc = stats.t.ppf(0.95, n - 1)
    mc = np.mean(((m + 0.1) / se > tc) & ((m - 0.1) / se < -tc))
    assert P.paired_tost_power(n, sd, 0.1, 0.02) == pytest.approx(mc, abs=0.02)


def test_noninferiority_power_is_statsmodels_ttestpower():
    ref = TTestPower().power(effect_size=0.1 / 0.24, nobs=37, alpha=0.05, alternative="larger")
    assert P.noninferiority_power(37, 0.24, 0.1, 0.0) == pytest.approx(ref, rel=1e-6)
