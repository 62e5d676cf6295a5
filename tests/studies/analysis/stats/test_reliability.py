"""Tests of ``studies.analysis.stats.reliability`` (moved from the suite on: studies.analysis
statistics: each function against the scipy/statsmodels call it names, and the paper's numbers
(shared/reference/studies.md) reproduced from the paper's summaries)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from studies.analysis import stats as S


def test_icc_oneway_matches_the_anova_formula():
    df = pd.DataFrame({"g": np.repeat([0, 1, 2], 3), "v": [1, 2, 3, 4, 5, 6, 8, 9, 7]})
    out = S.icc_oneway(df, "v", "g").iloc[0]
    msb = 3 * ((2 - 5) ** 2 + (5 - 5) ** 2 + (8 - 5) ** 2) / 2
    msw = 6 / 6
    assert out.icc == pytest.approx((msb - msw) / (msb + 2 * msw))
    assert out.design_effect == pytest.approx(1 + 2 * out.icc)
