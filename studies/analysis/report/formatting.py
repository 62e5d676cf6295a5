"""Numbers and tests frames formatted for people (p values, estimates with their intervals)."""

from __future__ import annotations

import numpy as np
import pandas as pd


def fmt_p(p: float) -> str:
    """A p value for people: 3 decimals, or 2 significant digits below 0.001."""
    if p is None or not np.isfinite(p):
        return "–"
    return f"{p:.2g}" if p < 0.001 else f"{p:.3f}"


def _num(x: float, digits: int = 3) -> str:
    return "–" if x is None or not np.isfinite(x) else f"{x:.{digits}f}"


def tests_table(tests: pd.DataFrame, digits: int = 3) -> pd.DataFrame:
    """The human-readable view of a tests frame (with its ``truth`` beside the estimate when it
    has one: see :mod:`studies.analysis.truth`)."""
    rows = []
    for r in tests.itertuples(index=False):
        if np.isfinite(r.estimate):
            hi = "∞" if r.ci_high == np.inf else _num(r.ci_high, digits)
            est = (
                f"{_num(r.estimate, digits)} [{_num(r.ci_low, digits)}, {hi}]"
                if np.isfinite(r.ci_low)
                else _num(r.estimate, digits)
            )
            lvl = f"{r.ci_level:.0%}" if np.isfinite(r.ci_level) else ""
        else:
            est, lvl = "–", ""
        row = {
            "approach": r.approach,
            "test": r.test,
            "n": ""
            if not np.isfinite(r.n)
            else f"{r.n:.0f}"
            + (f" ({r.clusters:.0f} clusters)" if np.isfinite(r.clusters) else ""),
            "estimate [CI]": est,
        }
        if "truth" in tests:  # simulated data: what the estimate should recover
            row["truth"] = _num(r.truth, digits)
        row |= {"CI": lvl, "p": fmt_p(r.p_value), "conclusion": r.conclusion}
        rows.append(row)
    return pd.DataFrame(rows)
