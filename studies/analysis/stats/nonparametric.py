"""Rank tests: the Wilcoxon signed-rank test of cluster means against a value, a check on the
t-test that does not take the 1-5 ratings as interval-scaled."""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

from studies.analysis.stats.common import (
    cluster_unit,
    decision,
    not_estimable,
    result_frame,
    values,
)


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
    means = df.assign(_v=values(df, value)).groupby(cluster)["_v"].mean().dropna()
    d = means.to_numpy() - popmean
    nz = d[d != 0]
    name = f"Wilcoxon signed-rank vs {popmean:g} on {cluster_unit(cluster)} means"
    if len(nz) < 1:
        return not_estimable(name, "every mean equals the neutral value", n=len(d))
    res = stats.wilcoxon(nz)
    p = float(res.pvalue)
    med = float(np.median(means))
    return result_frame(
        test=name,
        null_hypothesis=f"median = {popmean:g}",
        n=len(d),
        clusters=len(d),
        estimate=med,
        statistic=float(res.statistic),
        alpha=alpha,
        **decision(
            p,
            alpha,
            f"median {med:.2f} {'>' if med > popmean else '<'} {popmean:g}",
            f"not shown to differ from {popmean:g}",
        ),
        method="scipy wilcoxon (two-sided), zero differences dropped",
    )
