"""What every test of :mod:`studies.analysis.stats` shares: the result frame and the decision it
reports, reading a column, the logit, and the wording of p values and of a test that cannot be
run."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

TEST_COLUMNS: tuple[str, ...] = (
    "test",
    "null_hypothesis",
    "n",
    "clusters",
    "estimate",
    "ci_low",
    "ci_high",
    "ci_level",
    "statistic",
    "df",
    "p_value",
    "p_lower",
    "p_upper",
    "alpha",
    "reject",
    "conclusion",
    "method",
)


def tests_frame(rows: Sequence[dict]) -> pd.DataFrame:
    """Rows of test results as a frame with exactly the :data:`TEST_COLUMNS` (missing: NaN)."""
    out = pd.DataFrame(list(rows))
    for col in TEST_COLUMNS:
        if col not in out:
            out[col] = np.nan
    return out[list(TEST_COLUMNS)]


def result_frame(**fields) -> pd.DataFrame:
    """One test's result, ``fields`` named as :data:`TEST_COLUMNS`, as a one-row frame."""
    return tests_frame([fields])


def not_estimable(test: str, why: str, **fields) -> pd.DataFrame:
    """One result row saying why ``test`` could not be run (``conclusion: not estimable: why``)."""
    return result_frame(test=test, conclusion=f"not estimable: {why}", **fields)


def decision(p: float, alpha: float, shown: str, not_shown: str, caveat: str = "") -> dict:
    """The result-row fields of a test's decision at level ``alpha``: ``p_value``, ``reject``
    (``p < alpha``) and the conclusion: ``shown`` when the null is rejected, else ``not_shown``,
    each followed by the p value in brackets (and, when not shown, by ``caveat``)."""
    reject = p < alpha
    if reject:
        return dict(p_value=p, reject=reject, conclusion=f"{shown} ({format_p(p)})")
    return dict(p_value=p, reject=reject, conclusion=f"{not_shown} ({format_p(p)}){caveat}")


def interval(estimate: float, half: float, level: float) -> dict:
    """``estimate`` with the interval ``estimate ± half`` at ``level``, as result-row fields."""
    return dict(estimate=estimate, ci_low=estimate - half, ci_high=estimate + half, ci_level=level)


def values(df: pd.DataFrame, column: str) -> np.ndarray:
    """``df[column]`` as floats (unparsable: NaN); a missing column is named with the others."""
    if column not in df:
        raise KeyError(
            f"column {column!r} not in the frame (columns: {', '.join(map(str, df.columns))})"
        )
    return pd.to_numeric(df[column], errors="coerce").to_numpy(dtype=float)


def successes(df: pd.DataFrame, column: str) -> tuple[int, int]:
    """``(k, n)``: the 1s among the 0/1 outcomes of ``df[column]`` and the number of outcomes
    (missing ones dropped); anything but 0/1 is an error."""
    y = values(df, column)
    y = y[~np.isnan(y)]
    if not np.isin(y, (0.0, 1.0)).all():
        raise ValueError(f"column {column!r} must hold 0/1 (or true/false) outcomes")
    return int(y.sum()), len(y)


def logit(p: float | np.ndarray) -> float | np.ndarray:
    """log(p / (1 - p))."""
    return np.log(p) - np.log1p(-p)


def expit(x: float | np.ndarray) -> float | np.ndarray:
    """1 / (1 + exp(-x))."""
    return 1.0 / (1.0 + np.exp(-x))


def cluster_unit(cluster: str) -> str:
    """How a cluster column reads in a test name: ``participant_id`` -> ``participant``."""
    return cluster[:-3] if cluster.endswith("_id") else cluster


def format_p(p: float) -> str:
    """``p = 0.012``, ``p = 3.4e-05`` below 0.001, ``p = n/a`` when not finite."""
    if not np.isfinite(p):
        return "p = n/a"
    return f"p = {p:.2g}" if p < 0.001 else f"p = {p:.3f}"


def constant(x: np.ndarray) -> bool:
    """Every value of ``x`` the same, up to round-off (e.g. rates 1/3 and 2/6)."""
    x = np.asarray(x, dtype=float)
    return len(x) == 0 or float(np.ptp(x)) <= 1e-12 * max(1.0, float(np.max(np.abs(x))))


def no_spread(x: np.ndarray, every: str) -> str:
    """Why a t statistic cannot be formed from ``x`` ("" when it can): fewer than 2 values, or no
    spread (every value the same, up to round-off), where t = (mean - m) / 0 is not a test."""
    if len(x) < 2:
        return f"needs at least 2 values, got {len(x)}"
    if constant(x):
        return f"{every} is {float(np.mean(x)):.3g} (zero variance: no t-test or interval)"
    return ""
