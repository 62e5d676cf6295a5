"""t-tests: one sample against a value (on every row, or on cluster means), two independent
groups (the paper's study-2 test), and the paired comparison of two conditions with its TOST and
non-inferiority test."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pandas as pd
from scipy import stats

from studies.analysis.stats.common import (
    cluster_unit,
    constant,
    decision,
    interval,
    no_spread,
    not_estimable,
    result_frame,
    tests_frame,
    values,
)
from studies.analysis.stats.equivalence import noninferiority_fields, tost_fields


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

    Examples
    --------
    Confidence ratings of four participants, two each, against the scale's midpoint 3:

    >>> import pandas as pd
    >>> from studies.analysis.stats import one_sample_ttest
    >>> ratings = pd.DataFrame(
    ...     {"confidence": [4, 5, 3, 4, 4, 5, 2, 4], "participant_id": list("aabbccdd")}
    ... )
    >>> row = one_sample_ttest(ratings, popmean=3.0, cluster="participant_id").iloc[0]
    >>> int(row["n"]), float(row["estimate"]), round(float(row["statistic"]), 3)
    (4, 3.875, 2.333)
    >>> round(float(row["p_value"]), 3)
    0.102
    """
    if cluster is None:
        x = values(df, value)
        x = x[~np.isnan(x)]
        unit, n_clusters = "ratings", np.nan
    else:
        means = df.assign(_v=values(df, value)).groupby(cluster)["_v"].mean().dropna()
        x = means.to_numpy()
        unit, n_clusters = f"{cluster_unit(cluster)} means", len(x)
    n = len(x)
    null = {"greater": "<=", "less": ">=", "two-sided": "="}[alternative]
    name = f"one-sample t-test vs {popmean:g} on {unit}"
    common = dict(null_hypothesis=f"mean {null} {popmean:g}", n=n, clusters=n_clusters, alpha=alpha)
    why = no_spread(x, f"every {unit[:-1]}")  # "ratings" / "participant means"
    if why:
        estimate = float(np.mean(x)) if n else np.nan
        return not_estimable(
            name, why, estimate=estimate, method="scipy ttest_1samp not run", **common
        )
    res = stats.ttest_1samp(x, popmean, alternative=alternative)
    mean = float(np.mean(x))
    se = float(np.std(x, ddof=1) / math.sqrt(n))
    q = stats.t.ppf(1 - alpha / 2, n - 1)
    shown = f"mean {mean:.2f} {'>' if mean > popmean else '<'} {popmean:g}"
    if alternative == "two-sided":
        not_shown = f"not shown to differ from {popmean:g}"
    else:
        not_shown = f"not shown that mean {'>' if alternative == 'greater' else '<'} {popmean:g}"
    per = (
        "; all rows independent" if cluster is None else f"; one value per {cluster_unit(cluster)}"
    )
    return result_frame(
        test=name,
        **common,
        **interval(mean, q * se, 1 - alpha),
        statistic=float(res.statistic),
        df=n - 1,
        **decision(float(res.pvalue), alpha, shown, not_shown),
        method=f"scipy ttest_1samp ({alternative})" + per,
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
    name = f"independent t-test on {unit} rates ({levels[1]} - {levels[0]})"
    rates = df.assign(_y=values(df, outcome)).groupby([group, unit])["_y"].mean()
    present = set(rates.index.get_level_values(0))
    if not set(levels) <= present or min(len(rates.loc[lv]) for lv in levels) < 2:
        why = f"needs at least 2 {unit}s for each of {', '.join(levels)}"
        return not_estimable(name, why, alpha=alpha)
    a = rates.loc[levels[0]].to_numpy()
    b = rates.loc[levels[1]].to_numpy()
    null = f"{levels[1]} rate = {levels[0]} rate"
    if constant(a) and constant(b):
        return not_estimable(
            name,
            f"every {levels[0]} {unit} rate is {a.mean():.3g} and every "
            f"{levels[1]} {unit} rate is {b.mean():.3g} (zero variance: no t-test or interval)",
            null_hypothesis=null,
            n=len(a) + len(b),
            estimate=float(b.mean() - a.mean()),
            alpha=alpha,
            method="scipy ttest_ind not run",
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
    return result_frame(
        test=name,
        null_hypothesis=null,
        n=len(a) + len(b),
        **interval(diff, q * se, 1 - alpha),
        statistic=float(res.statistic),
        df=dof,
        alpha=alpha,
        **decision(
            float(res.pvalue),
            alpha,
            f"{levels[1]} and {levels[0]} differ",
            "difference not shown",
            "; this is not evidence of equality",
        ),
        method=f"scipy ttest_ind (equal_var={equal_var}) on {len(a)}+{len(b)} {unit} rates; ignores pairing",
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

    wide = df.assign(_y=values(df, outcome)).pivot_table(
        index=cluster, columns=condition, values="_y", aggfunc="mean", observed=True
    )
    missing = [lv for lv in levels if lv not in wide.columns]
    base = dict(alpha=alpha)
    label = f"{levels[1]} - {levels[0]}"
    unit = cluster_unit(cluster)
    name = f"paired t-test by {unit} ({label})"
    if missing:
        return not_estimable(name, f"no {missing[0]} rows", **base)
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
    if n < 3 or constant(d):
        why = (
            "fewer than 3 pairs"
            if n < 3
            else f"every {unit}'s paired difference is {d[0]:.3g} (zero variance: no t-test or interval)"
        )
        estimate = float(d.mean()) if n else np.nan
        return not_estimable(
            name, why, null_hypothesis=f"{label} = 0", estimate=estimate, method=note, **base
        )
    mean = float(d.mean())
    se = float(np.std(d, ddof=1)) / math.sqrt(n)
    q = stats.t.ppf(1 - alpha / 2, n - 1)
    q2 = stats.t.ppf(1 - alpha, n - 1)
    tt = stats.ttest_rel(a, b)
    p_t, (t1, p1, _), (t2, p2, _) = ttost_paired(a, b, -margin, margin)
    p_t, p1, p2 = float(p_t), float(p1), float(p2)
    ni = stats.ttest_1samp(d, -margin, alternative="greater")
    p_ni = float(ni.pvalue)
    direction = "higher" if mean > 0 else "lower"
    rows = [
        dict(
            test=name,
            null_hypothesis=f"{label} = 0",
            **interval(mean, q * se, 1 - alpha),
            statistic=float(tt.statistic),
            df=n - 1,
            **decision(
                float(tt.pvalue),
                alpha,
                f"{levels[1]} {direction} than {levels[0]}",
                "difference not shown",
                "; not evidence of equality",
            ),
            method="scipy ttest_rel; " + note,
            **base,
        ),
        dict(
            test=f"paired TOST by {unit} (±{margin:g})",
            null_hypothesis=f"{label} <= {-margin:g} or >= {margin:g}",
            estimate=mean,
            statistic=float(min(abs(t1), abs(t2))),
            df=n - 1,
            **tost_fields(
                "difference", (mean - q2 * se, mean + q2 * se), p_t, p1, p2, -margin, margin, alpha
            ),
            method="statsmodels ttost_paired; " + note,
            **base,
        ),
        dict(
            test=f"non-inferiority by {unit} (margin {margin:g})",
            estimate=mean,
            statistic=float(ni.statistic),
            df=n - 1,
            **noninferiority_fields(
                label,
                margin,
                mean - q2 * se,
                p_ni,
                alpha,
                f"non-inferior: {levels[1]} no worse than {levels[0]} by {margin:g} or more",
            ),
            method="scipy ttest_1samp (greater) on paired differences; " + note,
            **base,
        ),
    ]
    return tests_frame(rows)
