"""Tests of ``studies.analysis.stats.mixed`` (moved from the suite on: studies.analysis statistics:
each function against the scipy/statsmodels call it names, and the paper's numbers
(shared/reference/studies.md) reproduced from the paper's summaries)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from studies.analysis import stats as S
from studies.analysis.paper import (
    paper_turing_frame,
)
from tests.helpers.study_analysis import binary_frame


def test_mixed_logit_recovers_a_crossed_model_and_reports_its_caveat():
    rng = np.random.default_rng(1)
    p, w = np.repeat(np.arange(60), 10), np.tile(np.arange(10), 60)
    eta = -0.5 + rng.normal(0, 0.7, 60)[p] + rng.normal(0, 0.3, 10)[w]
    df = pd.DataFrame(
        {
            "participant_id": p,
            "word": w,
            "y": (rng.random(600) < 1 / (1 + np.exp(-eta))).astype(float),
        }
    )
    out = S.mixed_logit(df, "y").set_index("term")
    assert out.loc["Intercept", "ci_low"] < -0.5 < out.loc["Intercept", "ci_high"]
    assert 0.4 < out.loc["sd(participant_id)", "post_mean"] < 1.1
    assert out["status"].str.startswith("ok (variational Bayes").all()


def test_mixed_logit_failure_is_a_row_not_an_exception(monkeypatch):
    from statsmodels.genmod.bayes_mixed_glm import BinomialBayesMixedGLM

    def boom(self, *a, **k):
        raise np.linalg.LinAlgError("singular matrix")

    monkeypatch.setattr(BinomialBayesMixedGLM, "fit_vb", boom)
    out = S.mixed_logit(paper_turing_frame(), "chose_robot")
    assert len(out) == 1 and out.status.iloc[0] == "failed: LinAlgError: singular matrix"
    same = S.mixed_logit(binary_frame(0, 100), "y")
    assert same.status.iloc[0].startswith("failed: every answer is 0")
