"""Tests of ``studies.analysis.stats.common``: the result frame, the decision at a level, reading
columns, the logit and the wording of p values, each against a hand-computed case or scipy."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import special

from studies.analysis.stats import common as C


def test_tests_frame_has_exactly_the_test_columns_in_order_missing_ones_nan():
    out = C.tests_frame([dict(test="a", p_value=0.5, extra=1), dict(test="b", n=3)])
    assert list(out.columns) == list(C.TEST_COLUMNS)
    assert out.test.tolist() == ["a", "b"]
    assert out.p_value.iloc[0] == 0.5 and np.isnan(out.p_value.iloc[1])
    assert np.isnan(out.n.iloc[0]) and out.n.iloc[1] == 3
    assert out.drop(columns=["test", "p_value", "n"]).isna().all().all()


def test_not_estimable_says_why_in_the_conclusion_and_keeps_other_fields():
    out = C.not_estimable("t-test", "too few", n=1, alpha=0.1)
    assert len(out) == 1 and list(out.columns) == list(C.TEST_COLUMNS)
    row = out.iloc[0]
    assert row.test == "t-test" and row.conclusion == "not estimable: too few"
    assert row.n == 1 and row.alpha == 0.1 and np.isnan(row.p_value)


@pytest.mark.parametrize(
    "p, alpha, reject, conclusion",
    [
        (0.01, 0.05, True, "shown (p = 0.010)"),
        (0.05, 0.05, False, "kept (p = 0.050); caveat"),  # p = alpha is not below it
        (0.0499, 0.05, True, "shown (p = 0.050)"),
        (0.2, 0.25, True, "shown (p = 0.200)"),
        (2e-5, 0.01, True, "shown (p = 2e-05)"),
        (0.3, 0.05, False, "kept (p = 0.300); caveat"),
    ],
)
def test_decision_rejects_below_alpha_and_words_the_conclusion(p, alpha, reject, conclusion):
    out = C.decision(p, alpha, "shown", "kept", "; caveat")
    assert out == dict(p_value=p, reject=reject, conclusion=conclusion)


def test_decision_without_caveat_adds_nothing():
    assert C.decision(0.5, 0.05, "shown", "kept")["conclusion"] == "kept (p = 0.500)"


def test_interval_is_estimate_plus_minus_half_at_its_level():
    assert C.interval(2.0, 0.5, 0.9) == dict(estimate=2.0, ci_low=1.5, ci_high=2.5, ci_level=0.9)


def test_values_reads_floats_unparsable_as_nan_and_names_a_missing_column():
    df = pd.DataFrame({"a": ["1", "x", 2.5], "b": [1, 2, 3]})
    got = C.values(df, "a")
    assert got.dtype == float and got[0] == 1.0 and np.isnan(got[1]) and got[2] == 2.5
    with pytest.raises(KeyError, match=r"column 'c' not in the frame \(columns: a, b\)"):
        C.values(df, "c")


def test_successes_counts_ones_drops_missing_and_refuses_other_values():
    df = pd.DataFrame({"y": [1, 0, 1, None, 1, 0]})
    assert C.successes(df, "y") == (3, 5)
    assert C.successes(pd.DataFrame({"y": [True, False, False]}), "y") == (1, 3)
    with pytest.raises(ValueError, match="column 'y' must hold 0/1"):
        C.successes(pd.DataFrame({"y": [0, 1, 2]}), "y")
    with pytest.raises(ValueError, match="must hold 0/1"):
        C.successes(pd.DataFrame({"y": [0.5, 1]}), "y")


def test_logit_and_expit_match_scipy_and_invert_each_other():
    p = np.array([1e-9, 0.2, 0.5, 0.9, 1 - 1e-9])
    np.testing.assert_allclose(C.logit(p), special.logit(p), rtol=1e-12)
    x = np.array([-30.0, -1.0, 0.0, 2.5, 30.0])
    np.testing.assert_allclose(C.expit(x), special.expit(x), rtol=1e-12)
    np.testing.assert_allclose(C.expit(C.logit(p)), p, rtol=1e-9)
    assert C.logit(0.2) == pytest.approx(np.log(0.25))


def test_cluster_unit_drops_a_trailing_id_only():
    assert C.cluster_unit("participant_id") == "participant"
    assert C.cluster_unit("word") == "word"
    assert C.cluster_unit("idea") == "idea"


@pytest.mark.parametrize(
    "p, text",
    [
        (0.0123, "p = 0.012"),
        (0.001, "p = 0.001"),  # not below 0.001: three decimals
        (0.000999, "p = 0.001"),
        (3.4e-5, "p = 3.4e-05"),
        (0.5, "p = 0.500"),
        (1.0, "p = 1.000"),
        (float("nan"), "p = n/a"),
        (float("inf"), "p = n/a"),
    ],
)
def test_format_p(p, text):
    assert C.format_p(p) == text


@pytest.mark.parametrize(
    "x, same",
    [
        ([], True),
        ([5.0], True),
        ([1 / 3, 2 / 6, 0.1 + 0.2 + 1 / 3 - 0.3], True),  # round-off only
        ([0.0, 1e-13], True),  # below the absolute floor of 1e-12
        ([0.0, 1e-11], False),
        ([1e6, 1e6 + 1e-7], True),  # relative to the largest magnitude
        ([1e6, 1e6 + 1e-5], False),
        ([-1e6, -1e6 - 1e-7], True),  # magnitude, not value
        ([1.0, 1.0, 1.5], False),
    ],
)
def test_constant_is_no_spread_up_to_round_off(x, same):
    assert C.constant(np.array(x)) is same


def test_no_spread_names_too_few_values_and_zero_variance():
    assert C.no_spread(np.array([4.0]), "every rating") == "needs at least 2 values, got 1"
    assert C.no_spread(np.array([]), "every rating") == "needs at least 2 values, got 0"
    assert (
        C.no_spread(np.array([4.0, 4.0, 4.0]), "every rating")
        == "every rating is 4 (zero variance: no t-test or interval)"
    )
    assert C.no_spread(np.array([4.0, 5.0]), "every rating") == ""


def test_constant_at_its_tolerance_and_on_booleans():
    assert C.constant(np.array([0.0, 1e-12])) is True  # exactly at the floor: no spread
    assert C.constant(np.array([0.0, 1.5e-12])) is False  # the floor is 1e-12, not 2e-12
    assert C.constant([True, True]) is True and C.constant([True, False]) is False
