"""Statistics for the two user studies: tidy frames in, tidy frames out.

Every function takes a long-format DataFrame (one row per trial) plus column names and returns
a tidy DataFrame. Test results share the columns of :data:`TEST_COLUMNS` (one row per test);
rate tables those of :func:`rates_by`.

Two families:

*Paper-faithful* — what the paper did, treating every trial as independent:
:func:`binomial_test` (exact, vs chance), :func:`binomial_tost` (exact binomial TOST),
:func:`one_sample_ttest` without ``cluster`` (H2 on all ratings), :func:`group_ttest`
(study 2: independent t-test on the words' success rates).

*Recommended* — what a careful reviewer asks for: :func:`rates_by` (per-participant and
per-word rates with Wilson CIs), :func:`gee_rate` (GEE on participants, test vs chance and TOST),
:func:`one_sample_ttest` with ``cluster`` (H2 on participant means), :func:`signed_rank_test`,
:func:`paired_tests` (paired t, paired TOST, non-inferiority), :func:`gee_difference`,
:func:`mixed_logit` (crossed participants x words, variational Bayes), :func:`icc_oneway`,
:func:`margin_warnings`.

The tests in ``tests/test_study_analysis*.py`` check each function against the scipy or
statsmodels call its docstring names.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

import numpy as np
import pandas as pd
from scipy import stats

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


def _values(df: pd.DataFrame, column: str) -> np.ndarray:
    if column not in df:
        raise KeyError(
            f"column {column!r} not in the frame (columns: {', '.join(map(str, df.columns))})"
        )
    return pd.to_numeric(df[column], errors="coerce").to_numpy(dtype=float)


def _binary(df: pd.DataFrame, column: str) -> np.ndarray:
    y = _values(df, column)
    y = y[~np.isnan(y)]
    if not np.isin(y, (0.0, 1.0)).all():
        raise ValueError(f"column {column!r} must hold 0/1 (or true/false) outcomes")
    return y


def logit(p: float | np.ndarray) -> float | np.ndarray:
    """log(p / (1 - p))."""
    return np.log(p) - np.log1p(-p)


def expit(x: float | np.ndarray) -> float | np.ndarray:
    """1 / (1 + exp(-x))."""
    return 1.0 / (1.0 + np.exp(-x))


def _unit(cluster: str) -> str:
    """How a cluster column reads in a test name: ``participant_id`` -> ``participant``."""
    return cluster[:-3] if cluster.endswith("_id") else cluster


def _fmt_p(p: float) -> str:
    if not np.isfinite(p):
        return "p = n/a"
    return f"p = {p:.2g}" if p < 0.001 else f"p = {p:.3f}"


def _no_spread(x: np.ndarray, every: str) -> str:
    """Why a t statistic cannot be formed from ``x`` ("" when it can): fewer than 2 values, or no
    spread (every value the same, up to round-off), where t = (mean - m) / 0 is not a test."""
    if len(x) < 2:
        return f"needs at least 2 values, got {len(x)}"
    if _constant(x):
        return f"{every} is {float(np.mean(x)):.3g} (zero variance: no t-test or interval)"
    return ""


def _constant(x: np.ndarray) -> bool:
    """Every value of ``x`` the same, up to round-off (e.g. rates 1/3 and 2/6)."""
    x = np.asarray(x, dtype=float)
    return len(x) == 0 or float(np.ptp(x)) <= 1e-12 * max(1.0, float(np.max(np.abs(x))))


# --------------------------------------------------------------------------- paper-faithful


def proportion_ci(k, n, alpha: float = 0.05, method: str = "wilson"):
    """``statsmodels``' ``proportion_confint``, with each interval made to contain its rate k/n.

    At k = n (k = 0) the Wilson and exact bounds are 1 (0) in exact arithmetic, but statsmodels
    returns them with round-off (1 - 1e-16), which puts the rate outside its own interval and
    gives a negative error bar: a word every participant got right is a real outcome."""
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
        One row (:data:`TEST_COLUMNS`).
    """
    y = _binary(df, outcome)
    k, n = int(y.sum()), len(y)
    res = stats.binomtest(k, n, chance, alternative=alternative)
    ci = stats.binomtest(k, n, chance).proportion_ci(confidence_level=1 - alpha, method="exact")
    reject = res.pvalue < alpha
    side = {"greater": ">", "less": "<", "two-sided": "!="}[alternative]
    if reject:
        conclusion = f"rate {k / n:.3f} {side} chance {chance:g} ({_fmt_p(res.pvalue)})"
    else:
        conclusion = f"not shown that rate {side} chance {chance:g} ({_fmt_p(res.pvalue)})"
    null = {"greater": "<=", "less": ">=", "two-sided": "="}[alternative]
    return tests_frame(
        [
            dict(
                test="exact binomial test vs chance",
                null_hypothesis=f"rate {null} {chance:g}",
                n=n,
                estimate=k / n,
                ci_low=ci.low,
                ci_high=ci.high,
                ci_level=1 - alpha,
                statistic=k,
                p_value=res.pvalue,
                alpha=alpha,
                reject=reject,
                conclusion=conclusion,
                method=f"scipy binomtest ({alternative}); two-sided Clopper-Pearson CI; trials independent",
            )
        ]
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
    y = _binary(df, outcome)
    k, n = int(y.sum()), len(y)
    rows = []
    for m in methods:
        lo, hi = proportion_ci(k, n, alpha=alpha, method=m)
        rows.append(dict(method=m, k=k, n=n, rate=k / n, ci_low=lo, ci_high=hi, ci_level=1 - alpha))
    return pd.DataFrame(rows)


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

    y = _binary(df, outcome)
    k, n = int(y.sum()), len(y)
    low, upp = chance - margin, chance + margin
    p, p_low, p_upp = (float(v) for v in binom_tost(k, n, low, upp))
    k_lo, k_hi = binom_tost_reject_interval(low, upp, n, alpha=alpha)
    lo, hi = proportion_confint(k, n, alpha=2 * alpha, method="beta")
    return tests_frame(
        [
            dict(
                test="exact binomial TOST vs chance",
                null_hypothesis=f"rate <= {low:.3g} or rate >= {upp:.3g}",
                n=n,
                estimate=k / n,
                ci_low=lo,
                ci_high=hi,
                ci_level=1 - 2 * alpha,
                statistic=k,
                p_value=p,
                p_lower=p_low,
                p_upper=p_upp,
                alpha=alpha,
                reject=p < alpha,
                conclusion=_tost_conclusion("rate", p, p_low, p_upp, low, upp, alpha),
                method=(
                    f"statsmodels binom_tost; trials independent; equivalence possible only for "
                    f"{k_lo:.0f} <= k <= {k_hi:.0f} of {n}"
                ),
            )
        ]
    )


def _tost_conclusion(
    what: str, p: float, p_low: float, p_upp: float, low: float, upp: float, alpha: float
) -> str:
    if p < alpha:
        return f"equivalent: {what} within ({low:.3g}, {upp:.3g}) ({_fmt_p(p)})"
    kept = []
    if p_low >= alpha:
        kept.append(f"'{what} <= {low:.3g}' ({_fmt_p(p_low)})")
    if p_upp >= alpha:
        kept.append(f"'{what} >= {upp:.3g}' ({_fmt_p(p_upp)})")
    return "equivalence not shown: null " + " and ".join(kept) + " not rejected"


def one_sample_ttest(
    df: pd.DataFrame,
    value: str = "confidence",
    popmean: float = 3.0,
    alternative: str = "two-sided",
    alpha: float = 0.05,
    cluster: str | None = None,
) -> pd.DataFrame:
    """One-sample t-test of the mean of ``value`` against ``popmean``.

    Without ``cluster`` every row counts as independent (the paper's H2 test). With
    ``cluster`` (e.g. ``participant_id``) the test runs on the cluster means, so each
    participant counts once (recommended).

    Reference: ``scipy.stats.ttest_1samp(x, popmean, alternative=...)``; the CI is the
    two-sided ``1 - alpha`` t interval of the mean.
    """
    if cluster is None:
        x = _values(df, value)
        x = x[~np.isnan(x)]
        unit, n_clusters = "ratings", np.nan
    else:
        means = df.assign(_v=_values(df, value)).groupby(cluster)["_v"].mean().dropna()
        x = means.to_numpy()
        unit, n_clusters = f"{_unit(cluster)} means", len(x)
    n = len(x)
    null = {"greater": "<=", "less": ">=", "two-sided": "="}[alternative]
    name = f"one-sample t-test vs {popmean:g} on {unit}"
    common = dict(
        test=name, null_hypothesis=f"mean {null} {popmean:g}", n=n, clusters=n_clusters, alpha=alpha
    )
    why = _no_spread(x, f"every {unit[:-1] if unit.endswith('s') else unit}")
    if why:
        return tests_frame(
            [
                dict(
                    **common,
                    estimate=float(np.mean(x)) if n else np.nan,
                    conclusion=f"not estimable: {why}",
                    method="scipy ttest_1samp not run",
                )
            ]
        )
    res = stats.ttest_1samp(x, popmean, alternative=alternative)
    mean = float(np.mean(x))
    se = float(np.std(x, ddof=1) / math.sqrt(n))
    q = stats.t.ppf(1 - alpha / 2, n - 1)
    p = float(res.pvalue)
    reject = bool(p < alpha)
    if reject:
        side = ">" if mean > popmean else "<"
        conclusion = f"mean {mean:.2f} {side} {popmean:g} ({_fmt_p(p)})"
    elif alternative == "two-sided":
        conclusion = f"not shown to differ from {popmean:g} ({_fmt_p(p)})"
    else:
        conclusion = f"not shown that mean {'>' if alternative == 'greater' else '<'} {popmean:g} ({_fmt_p(p)})"
    return tests_frame(
        [
            dict(
                **common,
                estimate=mean,
                ci_low=mean - q * se,
                ci_high=mean + q * se,
                ci_level=1 - alpha,
                statistic=float(res.statistic),
                df=n - 1,
                p_value=p,
                reject=reject,
                conclusion=conclusion,
                method=f"scipy ttest_1samp ({alternative})"
                + (
                    "; all rows independent"
                    if cluster is None
                    else f"; one value per {_unit(cluster)}"
                ),
            )
        ]
    )


def group_ttest(
    df: pd.DataFrame,
    outcome: str = "correct",
    group: str = "writer",
    unit: str = "word",
    levels: tuple[str, str] = ("human", "robot"),
    alpha: float = 0.05,
    equal_var: bool = True,
) -> pd.DataFrame:
    """Independent two-sample t-test on per-``unit`` rates of the two ``group`` levels.

    The paper's study-2 test: the words' success rates for human and robot writing compared
    as two independent samples (estimate = second level minus first).

    Reference: ``scipy.stats.ttest_ind(rates_b, rates_a, equal_var=...)``.
    """
    rates = df.assign(_y=_values(df, outcome)).groupby([group, unit])["_y"].mean()
    present = set(rates.index.get_level_values(0))
    if not set(levels) <= present or min(len(rates.loc[lv]) for lv in levels) < 2:
        return tests_frame(
            [
                dict(
                    test=f"independent t-test on {unit} rates ({levels[1]} - {levels[0]})",
                    alpha=alpha,
                    conclusion=f"not estimable: needs at least 2 {unit}s for each of {', '.join(levels)}",
                )
            ]
        )
    a = rates.loc[levels[0]].to_numpy()
    b = rates.loc[levels[1]].to_numpy()
    if _constant(a) and _constant(b):
        diff = float(b.mean() - a.mean())
        return tests_frame(
            [
                dict(
                    test=f"independent t-test on {unit} rates ({levels[1]} - {levels[0]})",
                    null_hypothesis=f"{levels[1]} rate = {levels[0]} rate",
                    n=len(a) + len(b),
                    estimate=diff,
                    alpha=alpha,
                    conclusion=(
                        f"not estimable: every {levels[0]} {unit} rate is {a.mean():.3g} and every "
                        f"{levels[1]} {unit} rate is {b.mean():.3g} (zero variance: no t-test or interval)"
                    ),
                    method="scipy ttest_ind not run",
                )
            ]
        )
    with warnings.catch_warnings():  # one group constant (a word everyone read) is fine
        warnings.filterwarnings("ignore", "Precision loss", RuntimeWarning)
        res = stats.ttest_ind(b, a, equal_var=equal_var)
    diff = float(b.mean() - a.mean())
    if equal_var:
        dof = len(a) + len(b) - 2
        sp2 = ((len(a) - 1) * a.var(ddof=1) + (len(b) - 1) * b.var(ddof=1)) / dof
        se = math.sqrt(sp2 * (1 / len(a) + 1 / len(b)))
    else:
        va, vb = a.var(ddof=1) / len(a), b.var(ddof=1) / len(b)
        se = math.sqrt(va + vb)
        dof = (va + vb) ** 2 / (va**2 / (len(a) - 1) + vb**2 / (len(b) - 1))
    q = stats.t.ppf(1 - alpha / 2, dof)
    p = float(res.pvalue)
    reject = p < alpha
    return tests_frame(
        [
            dict(
                test=f"independent t-test on {unit} rates ({levels[1]} - {levels[0]})",
                null_hypothesis=f"{levels[1]} rate = {levels[0]} rate",
                n=len(a) + len(b),
                estimate=diff,
                ci_low=diff - q * se,
                ci_high=diff + q * se,
                ci_level=1 - alpha,
                statistic=float(res.statistic),
                df=dof,
                p_value=p,
                alpha=alpha,
                reject=reject,
                conclusion=(
                    f"{levels[1]} and {levels[0]} differ ({_fmt_p(p)})"
                    if reject
                    else f"difference not shown ({_fmt_p(p)}); this is not evidence of equality"
                ),
                method=f"scipy ttest_ind (equal_var={equal_var}) on {len(a)}+{len(b)} {unit} rates; ignores pairing",
            )
        ]
    )


# --------------------------------------------------------------------------- recommended


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
    frame = df.assign(_y=_values(df, outcome)).dropna(subset=["_y"])
    g = frame.groupby(keys, sort=True)["_y"]
    out = pd.DataFrame({"n": g.size(), "k": g.sum()}).reset_index()
    out["k"] = out["k"].astype(int)
    out["rate"] = out["k"] / out["n"]
    lo, hi = proportion_ci(out["k"].to_numpy(), out["n"].to_numpy(), alpha=alpha)
    out["ci_low"], out["ci_high"], out["ci_level"] = lo, hi, 1 - alpha
    if chance is not None:
        p = [stats.binomtest(int(k), int(n), chance).pvalue for k, n in zip(out["k"], out["n"])]
        out["p_vs_chance"] = p
        out["p_holm"] = multipletests(p, method="holm")[1] if len(p) else []
    return out


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
    rho = (
        float(np.atleast_1d(res.model.cov_struct.dep_params)[0])
        if res.model.cov_struct.dep_params is not None
        else np.nan
    )
    return res, cov, rho, notes


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

    frame = df.assign(_y=_values(df, outcome)).dropna(subset=["_y"])
    y = frame["_y"].to_numpy()
    groups = pd.factorize(frame[cluster])[0]
    n, n_cl = len(y), int(groups.max() + 1) if len(y) else 0
    base = dict(n=n, clusters=n_cl, alpha=alpha)
    off = float(logit(chance))
    try:
        if n_cl < 2:
            raise ValueError(f"needs answers from at least 2 {_unit(cluster)}s")
        if y.min() == y.max():
            raise ValueError(f"every answer is {int(y[0])}: the log-odds are infinite")
        res, cov, rho, notes = _gee_fit(
            y, np.ones((n, 1)), groups, sm.families.Binomial(), np.full(n, off)
        )
        b, se = float(res.params[0]), float(res.bse[0])
        if not (np.isfinite(b) and np.isfinite(se) and se > 0):
            raise ValueError("no finite estimate")
    except Exception as err:  # report, do not crash
        msg = " ".join(str(err).split())[:200]
        rows = [dict(test="GEE rate vs chance", conclusion=f"not estimable: {msg}", **base)]
        if margin is not None:
            rows.append(dict(test="GEE TOST vs chance", conclusion=f"not estimable: {msg}", **base))
        return tests_frame(rows)
    method = f"GEE logit, exchangeable (working ICC {rho:.3f}), {cov} SE, {n_cl} clusters" + (
        "; " + "; ".join(notes) if notes else ""
    )
    z = b / se
    p = float(2 * stats.norm.sf(abs(z)))
    q = stats.norm.ppf(1 - alpha / 2)
    rate = float(expit(off + b))
    reject = p < alpha
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
            p_value=p,
            reject=reject,
            conclusion=(
                f"{side} chance ({_fmt_p(p)})"
                if reject
                else f"not shown to differ from chance ({_fmt_p(p)})"
            ),
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
        rows.append(
            dict(
                test="GEE TOST vs chance",
                null_hypothesis=f"rate <= {low:.3g} or rate >= {upp:.3g}",
                estimate=rate,
                ci_low=float(expit(off + b - q2 * se)),
                ci_high=float(expit(off + b + q2 * se)),
                ci_level=1 - 2 * alpha,
                statistic=z,
                p_value=p_t,
                p_lower=p_low,
                p_upper=p_upp,
                reject=p_t < alpha,
                conclusion=_tost_conclusion("rate", p_t, p_low, p_upp, low, upp, alpha),
                method=method,
                **base,
            )
        )
    return tests_frame(rows)


def signed_rank_test(
    df: pd.DataFrame,
    value: str = "confidence",
    popmean: float = 3.0,
    cluster: str = "participant_id",
    alpha: float = 0.05,
) -> pd.DataFrame:
    """Wilcoxon signed-rank test of the cluster means of ``value`` against ``popmean``.

    A check on the t-test that does not lean on the 1-5 ratings being interval-scaled.
    Reference: ``scipy.stats.wilcoxon(means - popmean)`` (two-sided; zero differences dropped).
    """
    means = df.assign(_v=_values(df, value)).groupby(cluster)["_v"].mean().dropna()
    d = means.to_numpy() - popmean
    nz = d[d != 0]
    if len(nz) < 1:
        return tests_frame(
            [
                dict(
                    test=f"Wilcoxon signed-rank vs {popmean:g} on {_unit(cluster)} means",
                    n=len(d),
                    conclusion="not estimable: every mean equals the neutral value",
                )
            ]
        )
    res = stats.wilcoxon(nz)
    p = float(res.pvalue)
    med = float(np.median(means))
    return tests_frame(
        [
            dict(
                test=f"Wilcoxon signed-rank vs {popmean:g} on {_unit(cluster)} means",
                null_hypothesis=f"median = {popmean:g}",
                n=len(d),
                clusters=len(d),
                estimate=med,
                statistic=float(res.statistic),
                p_value=p,
                alpha=alpha,
                reject=p < alpha,
                conclusion=(
                    f"median {med:.2f} {'>' if med > popmean else '<'} {popmean:g} ({_fmt_p(p)})"
                    if p < alpha
                    else f"not shown to differ from {popmean:g} ({_fmt_p(p)})"
                ),
                method="scipy wilcoxon (two-sided), zero differences dropped",
            )
        ]
    )


def paired_tests(
    df: pd.DataFrame,
    outcome: str = "correct",
    condition: str = "writer",
    cluster: str = "participant_id",
    levels: tuple[str, str] = ("human", "robot"),
    margin: float = 0.10,
    alpha: float = 0.05,
) -> pd.DataFrame:
    """Paired comparison of the two ``condition`` levels within each ``cluster``.

    Rates are averaged per cluster and level; clusters missing a level are dropped. The
    difference is ``levels[1] - levels[0]`` (robot minus human). Three rows:

    - paired t-test (two-sided, ``1 - alpha`` CI);
    - paired TOST: ``-margin < difference < margin`` (``1 - 2 alpha`` CI);
    - non-inferiority: ``difference > -margin`` (one-sided t-test at ``alpha``).

    With ``cluster="participant_id"`` this is the within-participant analysis; with
    ``cluster="word"`` the by-item analysis (each word read in both writings).

    Reference: ``scipy.stats.ttest_rel``, ``statsmodels.stats.weightstats.ttost_paired``,
    ``scipy.stats.ttest_1samp(d, -margin, alternative="greater")``.
    """
    from statsmodels.stats.weightstats import ttost_paired

    wide = df.assign(_y=_values(df, outcome)).pivot_table(
        index=cluster, columns=condition, values="_y", aggfunc="mean", observed=True
    )
    missing = [lv for lv in levels if lv not in wide.columns]
    base = dict(alpha=alpha)
    label = f"{levels[1]} - {levels[0]}"
    unit = _unit(cluster)
    if missing:
        return tests_frame(
            [
                dict(
                    test=f"paired t-test by {unit} ({label})",
                    conclusion=f"not estimable: no {missing[0]} rows",
                    **base,
                )
            ]
        )
    complete = wide.dropna(subset=list(levels))
    a = complete[levels[1]].to_numpy()
    b = complete[levels[0]].to_numpy()
    d = a - b
    n = len(d)
    base.update(n=n, clusters=n)
    dropped = len(wide) - n
    note = f"{n} {unit}s with both levels" + (
        f" ({dropped} dropped: one level only)" if dropped else ""
    )
    sd = float(np.std(d, ddof=1)) if n > 1 else np.nan
    if n < 3 or _constant(d):
        why = (
            "fewer than 3 pairs"
            if n < 3
            else f"every {unit}'s paired difference is {d[0]:.3g} (zero variance: no t-test or interval)"
        )
        return tests_frame(
            [
                dict(
                    test=f"paired t-test by {unit} ({label})",
                    null_hypothesis=f"{label} = 0",
                    estimate=float(d.mean()) if n else np.nan,
                    conclusion=f"not estimable: {why}",
                    method=note,
                    **base,
                )
            ]
        )
    mean = float(d.mean())
    se = sd / math.sqrt(n)
    q = stats.t.ppf(1 - alpha / 2, n - 1)
    q2 = stats.t.ppf(1 - alpha, n - 1)
    tt = stats.ttest_rel(a, b)
    p = float(tt.pvalue)
    p_t, (t1, p1, _), (t2, p2, _) = ttost_paired(a, b, -margin, margin)
    p_t, p1, p2 = float(p_t), float(p1), float(p2)
    ni = stats.ttest_1samp(d, -margin, alternative="greater")
    p_ni = float(ni.pvalue)
    direction = "higher" if mean > 0 else "lower"
    rows = [
        dict(
            test=f"paired t-test by {unit} ({label})",
            null_hypothesis=f"{label} = 0",
            estimate=mean,
            ci_low=mean - q * se,
            ci_high=mean + q * se,
            ci_level=1 - alpha,
            statistic=float(tt.statistic),
            df=n - 1,
            p_value=p,
            reject=p < alpha,
            conclusion=(
                f"{levels[1]} {direction} than {levels[0]} ({_fmt_p(p)})"
                if p < alpha
                else f"difference not shown ({_fmt_p(p)}); not evidence of equality"
            ),
            method="scipy ttest_rel; " + note,
            **base,
        ),
        dict(
            test=f"paired TOST by {unit} (±{margin:g})",
            null_hypothesis=f"{label} <= {-margin:g} or >= {margin:g}",
            estimate=mean,
            ci_low=mean - q2 * se,
            ci_high=mean + q2 * se,
            ci_level=1 - 2 * alpha,
            statistic=float(min(abs(t1), abs(t2))),
            df=n - 1,
            p_value=p_t,
            p_lower=p1,
            p_upper=p2,
            reject=p_t < alpha,
            conclusion=_tost_conclusion("difference", p_t, p1, p2, -margin, margin, alpha),
            method="statsmodels ttost_paired; " + note,
            **base,
        ),
        dict(
            test=f"non-inferiority by {unit} (margin {margin:g})",
            null_hypothesis=f"{label} <= {-margin:g}",
            estimate=mean,
            ci_low=mean - q2 * se,
            ci_high=np.inf,
            ci_level=1 - alpha,
            statistic=float(ni.statistic),
            df=n - 1,
            p_value=p_ni,
            reject=p_ni < alpha,
            conclusion=(
                f"non-inferior: {levels[1]} no worse than {levels[0]} by {margin:g} or more ({_fmt_p(p_ni)})"
                if p_ni < alpha
                else f"non-inferiority not shown ({_fmt_p(p_ni)})"
            ),
            method="scipy ttest_1samp (greater) on paired differences; " + note,
            **base,
        ),
    ]
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

    frame = df.assign(_y=_values(df, outcome)).dropna(subset=["_y"])
    frame = frame[frame[condition].isin(levels)]
    y = frame["_y"].to_numpy()
    x = (frame[condition] == levels[1]).to_numpy(dtype=float)
    groups = pd.factorize(frame[cluster])[0]
    label = f"{levels[1]} - {levels[0]}"
    base = dict(n=len(y), clusters=int(groups.max() + 1) if len(y) else 0, alpha=alpha)
    try:
        if base["clusters"] < 2:
            raise ValueError(f"needs answers from at least 2 {_unit(cluster)}s")
        if x.min() == x.max():
            raise ValueError(f"only one {condition} level present")
        fixed = {lv: float(y[x == i][0]) for i, lv in enumerate(levels) if _constant(y[x == i])}
        if len(fixed) == 2:  # the sandwich SE is 0: a Wald test would divide by it
            base["estimate"] = fixed[levels[1]] - fixed[levels[0]]
            raise ValueError(
                f"every answer is {y[0]:g} (no variation: the robust SE is 0)"
                if _constant(y)
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
        msg = " ".join(str(err).split())[:200]
        return tests_frame(
            [dict(test=f"GEE difference ({label})", conclusion=f"not estimable: {msg}", **base)]
        )
    method = f"GEE identity link, exchangeable (working ICC {rho:.3f}), {cov} SE" + (
        "; " + "; ".join(notes) if notes else ""
    )
    q, q2 = stats.norm.ppf(1 - alpha / 2), stats.norm.ppf(1 - alpha)
    z = d / se
    p = float(2 * stats.norm.sf(abs(z)))
    rows = [
        dict(
            test=f"GEE difference ({label})",
            null_hypothesis=f"{label} = 0",
            estimate=d,
            ci_low=d - q * se,
            ci_high=d + q * se,
            ci_level=1 - alpha,
            statistic=z,
            p_value=p,
            reject=p < alpha,
            conclusion=(
                f"{levels[1]} {'higher' if d > 0 else 'lower'} than {levels[0]} ({_fmt_p(p)})"
                if p < alpha
                else f"difference not shown ({_fmt_p(p)})"
            ),
            method=method,
            **base,
        )
    ]
    if margin is not None:
        p1 = float(stats.norm.sf((d + margin) / se))
        p2 = float(stats.norm.cdf((d - margin) / se))
        pt = max(p1, p2)
        rows.append(
            dict(
                test=f"GEE TOST (±{margin:g})",
                null_hypothesis=f"{label} <= {-margin:g} or >= {margin:g}",
                estimate=d,
                ci_low=d - q2 * se,
                ci_high=d + q2 * se,
                ci_level=1 - 2 * alpha,
                statistic=z,
                p_value=pt,
                p_lower=p1,
                p_upper=p2,
                reject=pt < alpha,
                conclusion=_tost_conclusion("difference", pt, p1, p2, -margin, margin, alpha),
                method=method,
                **base,
            )
        )
        rows.append(
            dict(
                test=f"GEE non-inferiority (margin {margin:g})",
                null_hypothesis=f"{label} <= {-margin:g}",
                estimate=d,
                ci_low=d - q2 * se,
                ci_high=np.inf,
                ci_level=1 - alpha,
                statistic=(d + margin) / se,
                p_value=p1,
                reject=p1 < alpha,
                conclusion=(
                    f"non-inferior ({_fmt_p(p1)})"
                    if p1 < alpha
                    else f"non-inferiority not shown ({_fmt_p(p1)})"
                ),
                method=method,
                **base,
            )
        )
    return tests_frame(rows)


def icc_oneway(df: pd.DataFrame, value: str, cluster: str = "participant_id") -> pd.DataFrame:
    """One-way ANOVA intraclass correlation ICC(1) of ``value`` within ``cluster``.

    ``ICC = (MSB - MSW) / (MSB + (n0 - 1) MSW)`` with ``n0`` the ANOVA mean cluster size
    for unequal sizes; the design effect is ``1 + (mean size - 1) ICC``, the factor by which
    treating every row as independent understates the variance of the mean.

    Returns
    -------
    DataFrame
        One row: value, icc, clusters, n, mean_cluster_size, design_effect.
    """
    frame = df.assign(_v=_values(df, value)).dropna(subset=["_v"])
    g = frame.groupby(cluster)["_v"]
    sizes, means = g.size().to_numpy(dtype=float), g.mean().to_numpy()
    k, n = len(sizes), float(sizes.sum())
    grand = frame["_v"].mean()
    ssb = float((sizes * (means - grand) ** 2).sum())
    ssw = float(((frame["_v"] - g.transform("mean")) ** 2).sum())
    if k < 2 or n - k < 1:
        icc = np.nan
    else:
        msb, msw = ssb / (k - 1), ssw / (n - k)
        n0 = (n - (sizes**2).sum() / n) / (k - 1)
        denom = msb + (n0 - 1) * msw
        icc = float((msb - msw) / denom) if denom > 0 else np.nan
    m = n / k if k else np.nan
    return pd.DataFrame(
        [
            dict(
                value=value,
                icc=icc,
                clusters=k,
                n=int(n),
                mean_cluster_size=m,
                design_effect=1 + (m - 1) * max(icc, 0.0) if np.isfinite(icc) else np.nan,
            )
        ]
    )


MIXED_COLUMNS = (
    "term",
    "type",
    "post_mean",
    "post_sd",
    "ci_low",
    "ci_high",
    "rate",
    "rate_low",
    "rate_high",
    "status",
)


def mixed_logit(
    df: pd.DataFrame,
    outcome: str = "chose_robot",
    participant: str = "participant_id",
    word: str = "word",
    fixed: str = "1",
    alpha: float = 0.05,
    max_levels: int = 600,
) -> pd.DataFrame:
    """Crossed random-effects logit: participants x words, fitted by variational Bayes.

    ``logit P(y) = fixed effects + u_participant + v_word`` with independent normal random
    intercepts, fitted with ``BinomialBayesMixedGLM.fit_vb`` (priors: fixed effects N(0, 2^2),
    log random-effect SDs N(0, 1)). Rows: each fixed effect (posterior mean, SD, approximate
    ``1 - alpha`` interval; ``rate`` columns = inverse logit, i.e. the rate of a typical
    participant on a typical word, *not* the population-average rate) and each random-effect
    SD. Never raises on a failed fit: one row with ``status`` saying why (``failed: ...``, or
    ``skipped: ...`` when participants + words exceed ``max_levels``: the fit time grows fast,
    about 9 s for 500 participants x 10 words on one core).

    Caveat: mean-field variational Bayes understates posterior uncertainty; the intervals are
    approximate and the GEE is the primary analysis.

    Reference: ``statsmodels.genmod.bayes_mixed_glm.BinomialBayesMixedGLM.from_formula(
    "y ~ fixed", {"participant": "0 + C(participant)", "word": "0 + C(word)"}, data).fit_vb()``
    (built here with a sparse random-effects design, so large files do not need a dense one).
    """
    from statsmodels.genmod.bayes_mixed_glm import BinomialBayesMixedGLM

    def failed(msg: str, why: str = "failed") -> pd.DataFrame:
        row = dict.fromkeys(MIXED_COLUMNS, np.nan)
        row.update(term="(model)", type="", status=f"{why}: {' '.join(msg.split())[:200]}")
        return pd.DataFrame([row])[list(MIXED_COLUMNS)]

    frame = df.assign(_y=_values(df, outcome)).dropna(subset=["_y"]).reset_index(drop=True)
    groups = [
        (name, pd.factorize(frame[col].astype(str)))
        for name, col in ((participant, participant), (word, word))
    ]
    groups = [(name, codes, levels) for name, (codes, levels) in groups if len(levels) > 1]
    if len(frame) < 10 or not groups:
        return failed("too few rows or clusters for a mixed model")
    if frame["_y"].nunique() < 2:
        return failed(f"every answer is {frame['_y'].iloc[0]:g}, so the log-odds are infinite")
    n_levels = sum(len(levels) for _, _, levels in groups)
    if n_levels > max_levels:
        return failed(
            f"{n_levels} participants and words is more than the variational fit handles quickly "
            f"(max_levels {max_levels}); the GEE results stand",
            "skipped",
        )
    status = "ok (variational Bayes: intervals approximate, likely too narrow)"
    try:
        from patsy import dmatrix
        from scipy import sparse

        exog = dmatrix(fixed, frame, return_type="dataframe")
        separated = _separated_cell(frame, exog, fixed)
        if separated:
            return failed(
                f"separation: {separated}, so the fixed effects' log-odds are infinite "
                "(a fit would report its prior, not the data)"
            )
        # one indicator column per participant and per word, built sparse (never dense)
        blocks, ident = [], []
        for k, (_, codes, levels) in enumerate(groups):
            n_lv = len(levels)
            blocks.append(
                sparse.csr_matrix(
                    (np.ones(len(codes)), (np.arange(len(codes)), codes)), shape=(len(codes), n_lv)
                )
            )
            ident += [k] * n_lv
        exog_vc = sparse.hstack(blocks, format="csr")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            model = BinomialBayesMixedGLM(
                frame["_y"].to_numpy(),
                exog.to_numpy(),
                exog_vc,
                np.asarray(ident),
                fep_names=list(exog.columns),
                vcp_names=[name for name, _, _ in groups],
            )
            res = model.fit_vb()
        if any("converge" in str(w.message).lower() for w in caught):
            status = (
                "converged with warnings (optimizer reported non-convergence); treat with caution"
            )
        fe_mean, fe_sd = np.asarray(res.fe_mean), np.asarray(res.fe_sd)
        vc_mean, vc_sd = np.asarray(res.vcp_mean), np.asarray(res.vcp_sd)
        if not (np.all(np.isfinite(fe_mean)) and np.all(np.isfinite(fe_sd))):
            return failed("non-finite posterior")
    except Exception as err:  # the report says so instead of crashing
        return failed(f"{type(err).__name__}: {err}")
    q = stats.norm.ppf(1 - alpha / 2)
    rows = []
    for name, m, s in zip(model.fep_names, fe_mean, fe_sd):
        lo, hi = m - q * s, m + q * s
        rows.append(
            dict(
                term=name,
                type="fixed (logit)",
                post_mean=m,
                post_sd=s,
                ci_low=lo,
                ci_high=hi,
                rate=float(expit(m)),
                rate_low=float(expit(lo)),
                rate_high=float(expit(hi)),
                status=status,
            )
        )
    for name, m, s in zip(model.vcp_names, vc_mean, vc_sd):
        # vcp are log SDs: report the SD and its interval
        rows.append(
            dict(
                term=f"sd({name})",
                type="random-effect SD (logit)",
                post_mean=float(np.exp(m)),
                post_sd=np.nan,
                ci_low=float(np.exp(m - q * s)),
                ci_high=float(np.exp(m + q * s)),
                rate=np.nan,
                rate_low=np.nan,
                rate_high=np.nan,
                status=status,
            )
        )
    return pd.DataFrame(rows)[list(MIXED_COLUMNS)]


def _separated_cell(frame: pd.DataFrame, exog: pd.DataFrame, fixed: str) -> str:
    """How the 0/1 outcome ``frame["_y"]`` is separated by the fixed-effects design ``exog``
    ("" when it is not): the answers of one cell of the design (one writer, say) all the same.
    For the categorical designs fitted here a constant cell is exactly (quasi-)separation."""
    cells = frame["_y"].groupby([exog[c].to_numpy() for c in exog.columns], sort=False)
    named = [c for c in frame.columns if c != "_y" and c in fixed]
    for _, y in cells:
        if y.nunique() == 1:
            first = frame.loc[y.index[0]]
            what = " ".join(str(first[c]) for c in named)
            return f"every {what + ' ' if what else ''}answer is {y.iloc[0]:g}"
    return ""


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
    y = _values(df, outcome)
    y = y[~np.isnan(y)]
    out: dict[str, float] = {}
    if len(y) > 1:
        p = float(y.mean())
        se = math.sqrt(p * (1 - p) / len(y))
        out["the CI half-width"] = float(stats.norm.ppf(1 - alpha / 2)) * se
        out["the standard error"] = se
    if word is not None and word in df:
        wr = df.assign(_y=_values(df, outcome)).groupby(word)["_y"].mean()
        if len(wr) > 1:
            out["the SD across words"] = float(wr.std(ddof=1))
    return out
