"""Rates of a 0/1 outcome: confidence intervals, the exact binomial test against chance (the
paper's, every trial independent) and rates per level of a column (with Holm-adjusted tests)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from scipy import stats

from studies.analysis.stats.common import decision, result_frame, successes, values


def proportion_ci(k, n, alpha: float = 0.05, method: str = "wilson"):
    """``statsmodels``' ``proportion_confint``, with each interval made to contain its rate k/n.

    At k = n (k = 0) the Wilson and exact bounds are 1 (0) in exact arithmetic, but statsmodels
    returns them with round-off (1 - 1e-16), which puts the rate outside its own interval and
    gives a negative error bar: a word every participant got right is a real outcome.

    Examples
    --------
    >>> low, high = proportion_ci(21, 50)  # Wilson, 95 %
    >>> round(low, 3), round(high, 3)
    (0.294, 0.558)
    >>> proportion_ci(10, 10)[1]  # never below the rate itself
    1.0
    """
    from statsmodels.stats.proportion import proportion_confint

    k_arr, n_arr = np.asarray(k, dtype=float), np.asarray(n, dtype=float)
    lo, hi = proportion_confint(k_arr, n_arr, alpha=alpha, method=method)
    rate = k_arr / n_arr
    lo, hi = np.minimum(lo, rate), np.maximum(hi, rate)
    if np.ndim(k) == 0:
        return float(lo), float(hi)
    return lo, hi


def binomial_test(
    df: pd.DataFrame,
    outcome: str = "chose_robot",
    chance: float = 0.2,
    alternative: str = "greater",
    alpha: float = 0.05,
) -> pd.DataFrame:
    """Exact binomial test of the rate of ``outcome`` against ``chance`` (all trials independent).

    Reference: ``scipy.stats.binomtest(k, n, chance, alternative)``; the CI is its exact
    (Clopper-Pearson) ``proportion_ci`` at ``1 - alpha``.

    Returns
    -------
    DataFrame
        One row (:data:`~studies.analysis.stats.common.TEST_COLUMNS`).

    Examples
    --------
    The paper's Turing question: 21 of 50 picks of the robot among five words, chance 1/5.

    >>> import pandas as pd
    >>> from studies.analysis.stats import binomial_test
    >>> trials = pd.DataFrame({"chose_robot": [1] * 21 + [0] * 29})
    >>> row = binomial_test(trials, chance=0.2).iloc[0]
    >>> float(row["estimate"]), round(float(row["ci_low"]), 3), round(float(row["ci_high"]), 3)
    (0.42, 0.282, 0.568)
    >>> bool(row["p_value"] < 0.001), bool(row["reject"])
    (True, True)
    """
    k, n = successes(df, outcome)
    res = stats.binomtest(k, n, chance, alternative=alternative)
    ci = stats.binomtest(k, n, chance).proportion_ci(confidence_level=1 - alpha, method="exact")
    side = {"greater": ">", "less": "<", "two-sided": "!="}[alternative]
    null = {"greater": "<=", "less": ">=", "two-sided": "="}[alternative]
    return result_frame(
        test="exact binomial test vs chance",
        null_hypothesis=f"rate {null} {chance:g}",
        n=n,
        estimate=k / n,
        ci_low=ci.low,
        ci_high=ci.high,
        ci_level=1 - alpha,
        statistic=k,
        alpha=alpha,
        **decision(
            res.pvalue,
            alpha,
            f"rate {k / n:.3f} {side} chance {chance:g}",
            f"not shown that rate {side} chance {chance:g}",
        ),
        method=f"scipy binomtest ({alternative}); two-sided Clopper-Pearson CI; trials independent",
    )


def proportion_intervals(
    df: pd.DataFrame,
    outcome: str = "chose_robot",
    alpha: float = 0.05,
    methods: Sequence[str] = ("beta", "wilson"),
) -> pd.DataFrame:
    """The rate of ``outcome`` with one CI per method (trials independent).

    Reference: ``statsmodels.stats.proportion.proportion_confint(k, n, alpha, method)``
    (``beta`` is the exact Clopper-Pearson interval).

    Returns
    -------
    DataFrame
        Columns method, k, n, rate, ci_low, ci_high, ci_level.
    """
    k, n = successes(df, outcome)
    rows = []
    for m in methods:
        lo, hi = proportion_ci(k, n, alpha=alpha, method=m)
        rows.append(dict(method=m, k=k, n=n, rate=k / n, ci_low=lo, ci_high=hi, ci_level=1 - alpha))
    return pd.DataFrame(rows)


def rates_by(
    df: pd.DataFrame,
    outcome: str,
    by: str | Sequence[str],
    alpha: float = 0.05,
    chance: float | None = None,
) -> pd.DataFrame:
    """Rate of ``outcome`` per level of ``by`` with Wilson CIs.

    With ``chance``, each level also gets a two-sided exact binomial test against it
    (``p_vs_chance``) and Holm-adjusted p values across the levels (``p_holm``).

    Reference: ``statsmodels.stats.proportion.proportion_confint(method="wilson")``,
    ``scipy.stats.binomtest``, ``statsmodels.stats.multitest.multipletests(method="holm")``.

    Returns
    -------
    DataFrame
        Columns ``*by``, n, k, rate, ci_low, ci_high, ci_level (and p_vs_chance, p_holm).
    """
    from statsmodels.stats.multitest import multipletests

    keys = [by] if isinstance(by, str) else list(by)
    frame = df.assign(_y=values(df, outcome)).dropna(subset=["_y"])
    g = frame.groupby(keys)["_y"]  # levels in sorted order
    out = pd.DataFrame({"n": g.size(), "k": g.sum()}).reset_index()
    out["k"] = out["k"].astype(int)
    out["rate"] = out["k"] / out["n"]
    lo, hi = proportion_ci(out["k"].to_numpy(), out["n"].to_numpy(), alpha=alpha)
    out["ci_low"], out["ci_high"], out["ci_level"] = lo, hi, 1 - alpha
    if chance is not None:
        p = [stats.binomtest(int(k), int(n), chance).pvalue for k, n in zip(out["k"], out["n"])]
        out["p_vs_chance"] = p
        out["p_holm"] = multipletests(p, method="holm")[1]
    return out
