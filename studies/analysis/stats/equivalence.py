"""Equivalence and non-inferiority: the exact binomial TOST against chance, what every TOST and
non-inferiority row says, and warnings about the equivalence margin itself."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy import stats

from studies.analysis.stats.common import decision, format_p, result_frame, successes, values


def tost_conclusion(
    what: str, p: float, p_low: float, p_upp: float, low: float, upp: float, alpha: float
) -> str:
    """The conclusion of a TOST of ``low < what < upp``: equivalent, or the null(s) kept."""
    if p < alpha:
        return f"equivalent: {what} within ({low:.3g}, {upp:.3g}) ({format_p(p)})"
    kept = []
    if p_low >= alpha:
        kept.append(f"'{what} <= {low:.3g}' ({format_p(p_low)})")
    if p_upp >= alpha:
        kept.append(f"'{what} >= {upp:.3g}' ({format_p(p_upp)})")
    return "equivalence not shown: null " + " and ".join(kept) + " not rejected"


def tost_fields(
    what: str,
    ci: tuple[float, float],
    p: float,
    p_low: float,
    p_upp: float,
    low: float,
    upp: float,
    alpha: float,
) -> dict:
    """The result-row fields of a TOST of ``low < what < upp``: its ``1 - 2 alpha`` interval
    ``ci``, the overall ``p`` (the larger one-sided one) and both one-sided p values, the
    decision at ``alpha`` and :func:`tost_conclusion`."""
    return dict(
        ci_low=ci[0],
        ci_high=ci[1],
        ci_level=1 - 2 * alpha,
        p_value=p,
        p_lower=p_low,
        p_upper=p_upp,
        reject=p < alpha,
        conclusion=tost_conclusion(what, p, p_low, p_upp, low, upp, alpha),
    )


def noninferiority_fields(
    label: str, margin: float, lower: float, p: float, alpha: float, shown: str
) -> dict:
    """The result-row fields of a non-inferiority test of ``label > -margin``: the one-sided
    ``1 - alpha`` interval from ``lower``, the decision and the conclusion (``shown`` when
    rejected)."""
    return dict(
        null_hypothesis=f"{label} <= {-margin:g}",
        ci_low=lower,
        ci_high=np.inf,
        ci_level=1 - alpha,
        **decision(p, alpha, shown, "non-inferiority not shown"),
    )


def binomial_tost(
    df: pd.DataFrame,
    outcome: str = "chose_robot",
    chance: float = 0.2,
    margin: float = 0.05,
    alpha: float = 0.05,
) -> pd.DataFrame:
    """Exact binomial TOST: is the rate within ``chance ± margin``? (trials independent)

    The two nulls are ``rate <= chance - margin`` (p_lower) and ``rate >= chance + margin``
    (p_upper); equivalence is shown when both are rejected (p = max). The conclusion names the
    null that was not rejected. The CI is the exact ``1 - 2 alpha`` interval, the range of
    counts that would show equivalence is in ``method``.

    Reference: ``statsmodels.stats.proportion.binom_tost(k, n, low, upp)`` and
    ``binom_tost_reject_interval(low, upp, n, alpha)``.
    """
    from statsmodels.stats.proportion import (
        binom_tost,
        binom_tost_reject_interval,
        proportion_confint,
    )

    k, n = successes(df, outcome)
    low, upp = chance - margin, chance + margin
    p, p_low, p_upp = (float(v) for v in binom_tost(k, n, low, upp))
    k_lo, k_hi = binom_tost_reject_interval(low, upp, n, alpha=alpha)
    ci = proportion_confint(k, n, alpha=2 * alpha, method="beta")
    return result_frame(
        test="exact binomial TOST vs chance",
        null_hypothesis=f"rate <= {low:.3g} or rate >= {upp:.3g}",
        n=n,
        estimate=k / n,
        statistic=k,
        alpha=alpha,
        **tost_fields("rate", ci, p, p_low, p_upp, low, upp, alpha),
        method=(
            f"statsmodels binom_tost; trials independent; equivalence possible only for "
            f"{k_lo:.0f} <= k <= {k_hi:.0f} of {n}"
        ),
    )


def margin_warnings(
    margin: float,
    margin_source: str,
    data_values: dict[str, float] | None = None,
    tolerance: float = 0.1,
) -> list[str]:
    """Warnings about the equivalence margin: derived from the data, or looks as if it were.

    A margin is circular when it is taken from the data it is then tested on (the paper's
    ``delta ≈ 0.057`` "defined according to the confidence interval of the results obtained").

    Parameters
    ----------
    margin : float
    margin_source : {"preregistered", "data", "unstated", "default"}
        ``data``: warn. ``default``: no margin was configured, warn. ``unstated``: a margin was
        given without saying where it came from: warn if it is within ``tolerance`` (relative)
        of any of ``data_values``. ``preregistered``: trusted.
    data_values : dict of str to float
        Quantities of the data a margin is often taken from (e.g. ``{"the 95 % CI half-width":
        0.043, "the SD across words": 0.057}``); see :func:`margin_candidates`.
    """
    out = []
    if margin_source == "data":
        out.append(
            f"the equivalence margin {margin:g} was derived from the data (margin_source: data); "
            "a margin taken from the results is circular: fix it before collecting data (preregister it)"
        )
    elif margin_source == "default":
        out.append(
            f"no equivalence margin was configured; the default {margin:g} was used. "
            "State the margin in the study config (and preregister it) before collecting data"
        )
    elif margin_source == "unstated":
        for what, v in (data_values or {}).items():
            if np.isfinite(v) and v > 0 and abs(margin - v) <= tolerance * v:
                out.append(
                    f"the margin {margin:g} (source not stated) is close to {what} of these data ({v:.3f}); "
                    "if it was chosen from them, the equivalence test is circular. Set margin_source: "
                    "preregistered in the study config if it was fixed in advance"
                )
    return out


def margin_candidates(
    df: pd.DataFrame, outcome: str, word: str | None = "word", alpha: float = 0.05
) -> dict[str, float]:
    """Quantities of a rate that a data-derived margin is often taken from (for :func:`margin_warnings`).

    The ``1 - alpha`` Wald CI half-width, the binomial standard error, and the SD of the
    per-``word`` rates.
    """
    y = values(df, outcome)
    y = y[~np.isnan(y)]
    out: dict[str, float] = {}
    if len(y) > 1:
        p = float(y.mean())
        se = math.sqrt(p * (1 - p) / len(y))
        out["the CI half-width"] = float(stats.norm.ppf(1 - alpha / 2)) * se
        out["the standard error"] = se
    if word is not None and word in df:
        wr = df.assign(_y=values(df, outcome)).groupby(word)["_y"].mean()
        if len(wr) > 1:
            out["the SD across words"] = float(wr.std(ddof=1))
    return out
