"""Tests of ``studies.analysis.crossed_logit`` (moved from the suite on: simulated participants
with known truth: the simulator honours the truth it is given, and the analysis reaches the
right conclusions from its responses)."""

from __future__ import annotations

import pytest

from studies.analysis.crossed_logit import moments as _moments
from studies.analysis.participants import (
    latent_parameters,
)


@pytest.mark.parametrize(
    ("rate", "icc", "word_icc"), [(0.2, 0.0, 0.0), (0.45, 0.1, 0.0), (0.2, 0.15, 0.02)]
)
def test_calibration_gives_the_stated_marginal_rate_and_iccs(rate, icc, word_icc):
    b0, su, sv = latent_parameters(rate, icc, word_icc)
    mean, var_u, var_v = _moments(b0, su, sv)
    assert mean == pytest.approx(rate, abs=1e-9)
    assert var_u / (rate * (1 - rate)) == pytest.approx(icc, abs=1e-7)
    assert var_v / (rate * (1 - rate)) == pytest.approx(word_icc, abs=1e-7)
