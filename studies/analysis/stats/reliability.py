"""Agreement within clusters: the one-way intraclass correlation ICC(1) and the design effect it
implies for a mean that treats every row as independent."""

from __future__ import annotations

import numpy as np
import pandas as pd

from studies.analysis.stats.common import values


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
    frame = df.assign(_v=values(df, value)).dropna(subset=["_v"])
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
                design_effect=1 + (m - 1) * np.maximum(icc, 0.0),  # NaN stays NaN
            )
        ]
    )
