"""Generalized estimating equations: answers clustered within participants (or words), the
population-average rate against chance and the difference between two conditions, each with
its TOST (and non-inferiority test) on a bias-reduced robust standard error."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
from scipy import stats

from studies.analysis.stats.common import (
    cluster_unit,
    constant,
    decision,
    expit,
    interval,
    logit,
    not_estimable,
    tests_frame,
    values,
)
from studies.analysis.stats.equivalence import noninferiority_fields, tost_fields


def _gee_fit(y, exog, groups, family, offset=None):
    """Fit an exchangeable GEE; bias-reduced (Mancl-DeRouen) sandwich when it is available."""
    import statsmodels.api as sm

    model = sm.GEE(
        y,
        exog,
        groups=groups,
        family=family,
        cov_struct=sm.cov_struct.Exchangeable(),
        offset=offset,
    )
    notes = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            res = model.fit(cov_type="bias_reduced")
            cov = "bias-reduced robust"
        except Exception:  # bias reduction needs invertible cluster blocks
            res = model.fit(cov_type="robust")
            cov = "robust"
    if any("converge" in str(w.message).lower() for w in caught):
        notes.append("GEE did not fully converge")
    if groups.max() + 1 < 20:
        notes.append("fewer than 20 clusters: the robust SE is unreliable")
    rho = float(np.atleast_1d(res.model.cov_struct.dep_params)[0])  # Exchangeable: a float
    return res, cov, rho, notes


def _method(head: str, notes: list[str]) -> str:
    """``head`` and the fit's notes, as a result row's ``method``."""
    return head + ("; " + "; ".join(notes) if notes else "")


def _message(err: Exception) -> str:
    """Why a fit failed, on one line of at most 200 characters."""
    return " ".join(str(err).split())[:200]


def gee_rate(
    df: pd.DataFrame,
    outcome: str = "chose_robot",
    cluster: str = "participant_id",
    chance: float = 0.2,
    margin: float | None = None,
    alpha: float = 0.05,
) -> pd.DataFrame:
    """Population-average rate with answers clustered within ``cluster`` (GEE, logit link).

    Fits ``logit P(y) = logit(chance) + b`` (intercept only, offset at chance) with an
    exchangeable working correlation and a bias-reduced sandwich covariance, so ``b = 0`` is
    "rate = chance". Row 1: two-sided Wald test of ``b = 0``, 95 % CI on the rate scale.
    Row 2 (with ``margin``): TOST of ``chance - margin < rate < chance + margin`` on the logit
    scale (CI at ``1 - 2 alpha``). ``method`` carries the working correlation (the ICC of the
    0/1 answers within a cluster).

    Reference: ``statsmodels.api.GEE(..., family=Binomial(), cov_struct=Exchangeable(),
    offset=logit(chance))``.
    """
    import statsmodels.api as sm

    frame = df.assign(_y=values(df, outcome)).dropna(subset=["_y"])
    y = frame["_y"].to_numpy()
    groups = pd.factorize(frame[cluster])[0]
    n, n_cl = len(y), int(groups.max() + 1) if len(y) else 0
    base = dict(n=n, clusters=n_cl, alpha=alpha)
    off = float(logit(chance))
    try:
        if n_cl < 2:
            raise ValueError(f"needs answers from at least 2 {cluster_unit(cluster)}s")
        if y.min() == y.max():
            raise ValueError(f"every answer is {int(y[0])}: the log-odds are infinite")
        res, cov, rho, notes = _gee_fit(
            y, np.ones((n, 1)), groups, sm.families.Binomial(), np.full(n, off)
        )
        b, se = float(res.params[0]), float(res.bse[0])
        if not (np.isfinite(b) and np.isfinite(se) and se > 0):
            raise ValueError("no finite estimate")
    except Exception as err:  # report, do not crash
        names = ["GEE rate vs chance"] + (["GEE TOST vs chance"] if margin is not None else [])
        why = f"not estimable: {_message(err)}"
        return tests_frame([dict(test=name, conclusion=why, **base) for name in names])
    method = _method(
        f"GEE logit, exchangeable (working ICC {rho:.3f}), {cov} SE, {n_cl} clusters", notes
    )
    z = b / se
    p = float(2 * stats.norm.sf(abs(z)))
    q = stats.norm.ppf(1 - alpha / 2)
    rate = float(expit(off + b))
    side = "above" if b > 0 else "below"
    rows = [
        dict(
            test="GEE rate vs chance",
            null_hypothesis=f"rate = {chance:g}",
            estimate=rate,
            ci_low=float(expit(off + b - q * se)),
            ci_high=float(expit(off + b + q * se)),
            ci_level=1 - alpha,
            statistic=z,
            **decision(p, alpha, f"{side} chance", "not shown to differ from chance"),
            method=method,
            **base,
        )
    ]
    if margin is not None:
        low, upp = chance - margin, chance + margin
        lo_b, up_b = float(logit(low)) - off, float(logit(upp)) - off
        p_low = float(stats.norm.sf((b - lo_b) / se))
        p_upp = float(stats.norm.cdf((b - up_b) / se))
        p_t = max(p_low, p_upp)
        q2 = stats.norm.ppf(1 - alpha)
        ci = (float(expit(off + b - q2 * se)), float(expit(off + b + q2 * se)))
        rows.append(
            dict(
                test="GEE TOST vs chance",
                null_hypothesis=f"rate <= {low:.3g} or rate >= {upp:.3g}",
                estimate=rate,
                statistic=z,
                **tost_fields("rate", ci, p_t, p_low, p_upp, low, upp, alpha),
                method=method,
                **base,
            )
        )
    return tests_frame(rows)


def gee_difference(
    df: pd.DataFrame,
    outcome: str = "correct",
    condition: str = "writer",
    cluster: str = "participant_id",
    levels: tuple[str, str] = ("human", "robot"),
    margin: float | None = None,
    alpha: float = 0.05,
) -> pd.DataFrame:
    """Difference in rates (``levels[1] - levels[0]``) with answers clustered in ``cluster``.

    GEE with identity link on the 0/1 answers (a linear probability model), exchangeable working
    correlation and bias-reduced sandwich SE: the difference comes out on the rate scale where
    the margin lives. Rows: two-sided Wald test of no difference, and with ``margin`` a TOST
    and a non-inferiority test (normal reference).

    Reference: ``statsmodels.api.GEE(y, [1, is_robot], groups, family=Gaussian(),
    cov_struct=Exchangeable())``.
    """
    import statsmodels.api as sm

    frame = df.assign(_y=values(df, outcome)).dropna(subset=["_y"])
    frame = frame[frame[condition].isin(levels)]
    y = frame["_y"].to_numpy()
    x = (frame[condition] == levels[1]).to_numpy(dtype=float)
    groups = pd.factorize(frame[cluster])[0]
    label = f"{levels[1]} - {levels[0]}"
    base = dict(n=len(y), clusters=int(groups.max() + 1) if len(y) else 0, alpha=alpha)
    try:
        if base["clusters"] < 2:
            raise ValueError(f"needs answers from at least 2 {cluster_unit(cluster)}s")
        if x.min() == x.max():
            raise ValueError(f"only one {condition} level present")
        fixed = {lv: float(y[x == i][0]) for i, lv in enumerate(levels) if constant(y[x == i])}
        if len(fixed) == 2:  # the sandwich SE is 0: a Wald test would divide by it
            base["estimate"] = fixed[levels[1]] - fixed[levels[0]]
            raise ValueError(
                f"every answer is {y[0]:g} (no variation: the robust SE is 0)"
                if constant(y)
                else f"every {levels[1]} answer is {fixed[levels[1]]:g} and every {levels[0]} "
                f"answer is {fixed[levels[0]]:g} (perfect separation: the robust SE is 0)"
            )
        exog = np.column_stack([np.ones_like(x), x])
        res, cov, rho, notes = _gee_fit(y, exog, groups, sm.families.Gaussian())
        for lv, v in fixed.items():
            notes.append(
                f"every {lv} answer is {v:g}: the robust SE takes that rate as known exactly "
                "(interval too narrow; prefer the paired tests)"
            )
        d, se = float(res.params[1]), float(res.bse[1])
        if not (np.isfinite(se) and se > 0):
            raise ValueError("no finite standard error (all answers identical?)")
    except Exception as err:
        return not_estimable(f"GEE difference ({label})", _message(err), **base)
    method = _method(f"GEE identity link, exchangeable (working ICC {rho:.3f}), {cov} SE", notes)
    q, q2 = stats.norm.ppf(1 - alpha / 2), stats.norm.ppf(1 - alpha)
    z = d / se
    p = float(2 * stats.norm.sf(abs(z)))
    rows = [
        dict(
            test=f"GEE difference ({label})",
            null_hypothesis=f"{label} = 0",
            **interval(d, q * se, 1 - alpha),
            statistic=z,
            **decision(
                p,
                alpha,
                f"{levels[1]} {'higher' if d > 0 else 'lower'} than {levels[0]}",
                "difference not shown",
            ),
            method=method,
            **base,
        )
    ]
    if margin is not None:
        p1 = float(stats.norm.sf((d + margin) / se))
        p2 = float(stats.norm.cdf((d - margin) / se))
        pt = max(p1, p2)
        ci = (d - q2 * se, d + q2 * se)
        rows.append(
            dict(
                test=f"GEE TOST (±{margin:g})",
                null_hypothesis=f"{label} <= {-margin:g} or >= {margin:g}",
                estimate=d,
                statistic=z,
                **tost_fields("difference", ci, pt, p1, p2, -margin, margin, alpha),
                method=method,
                **base,
            )
        )
        rows.append(
            dict(
                test=f"GEE non-inferiority (margin {margin:g})",
                estimate=d,
                statistic=(d + margin) / se,
                **noninferiority_fields(label, margin, d - q2 * se, p1, alpha, "non-inferior"),
                method=method,
                **base,
            )
        )
    return tests_frame(rows)
