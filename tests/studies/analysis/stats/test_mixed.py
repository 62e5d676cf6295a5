"""Tests of ``studies.analysis.stats.mixed`` (moved from the suite on: studies.analysis statistics:
each function against the scipy/statsmodels call it names, and the paper's numbers
(shared/reference/studies.md) reproduced from the paper's summaries)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

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


# --------------------------------------------------------------------------- against statsmodels


# the two fits run the same optimiser on differently built designs: they agree to its tolerance
VB = dict(rtol=1e-3, atol=1e-4)


def _crossed(seed=1, participants=30, words=8, writer=False):
    rng = np.random.default_rng(seed)
    p, w = np.repeat(np.arange(participants), words), np.tile(np.arange(words), participants)
    robot = (w % 2).astype(float)
    eta = (
        -0.3
        + 0.8 * robot * writer
        + rng.normal(0, 0.7, participants)[p]
        + rng.normal(0, 0.4, words)[w]
    )
    return pd.DataFrame(
        {
            "pid": [f"P{i}" for i in p],
            "item": [f"w{i}" for i in w],
            "writer": np.where(robot == 1, "robot", "human"),
            "y": (rng.random(len(p)) < 1 / (1 + np.exp(-eta))).astype(float),
        }
    )


def test_mixed_logit_is_statsmodels_crossed_fit_vb_with_its_intervals():
    from scipy import stats
    from statsmodels.genmod.bayes_mixed_glm import BinomialBayesMixedGLM

    df = _crossed(writer=True)
    out = S.mixed_logit(df, "y", "pid", "item", fixed="C(writer)", alpha=0.1).set_index("term")
    ref = BinomialBayesMixedGLM.from_formula(
        "y ~ C(writer)", {"pid": "0 + C(pid)", "item": "0 + C(item)"}, df
    ).fit_vb()
    q = stats.norm.ppf(0.95)
    fe = ["Intercept", "C(writer)[T.robot]"]
    np.testing.assert_allclose(out.loc[fe, "post_mean"], ref.fe_mean, **VB)
    np.testing.assert_allclose(out.loc[fe, "post_sd"], ref.fe_sd, **VB)
    np.testing.assert_allclose(out.loc[fe, "ci_low"], ref.fe_mean - q * ref.fe_sd, **VB)
    np.testing.assert_allclose(out.loc[fe, "ci_high"], ref.fe_mean + q * ref.fe_sd, **VB)
    expit = 1 / (1 + np.exp(-out.loc[fe, ["post_mean", "ci_low", "ci_high"]].to_numpy()))
    np.testing.assert_allclose(out.loc[fe, ["rate", "rate_low", "rate_high"]], expit, rtol=1e-12)
    assert (out.loc[fe, "type"] == "fixed (logit)").all()
    vc = ["sd(pid)", "sd(item)"]
    names = list(ref.model.vcp_names)
    order = [names.index("pid"), names.index("item")]
    m, s = np.asarray(ref.vcp_mean)[order], np.asarray(ref.vcp_sd)[order]
    np.testing.assert_allclose(out.loc[vc, "post_mean"], np.exp(m), **VB)
    np.testing.assert_allclose(out.loc[vc, "ci_low"], np.exp(m - q * s), **VB)
    np.testing.assert_allclose(out.loc[vc, "ci_high"], np.exp(m + q * s), **VB)
    assert out.loc[vc, ["post_sd", "rate", "rate_low", "rate_high"]].isna().all().all()
    assert (out.loc[vc, "type"] == "random-effect SD (logit)").all()
    assert list(out.reset_index().columns) == list(S.MIXED_COLUMNS)
    assert (out.status == "ok (variational Bayes: intervals approximate, likely too narrow)").all()


def test_mixed_logit_default_level_and_one_grouping_when_the_other_has_one_level():
    from scipy import stats

    df = _crossed().rename(columns={"pid": "participant_id", "item": "word", "y": "chose_robot"})
    out = S.mixed_logit(df).set_index("term")
    row = out.loc["Intercept"]
    q = stats.norm.ppf(0.975)
    assert row.ci_low == pytest.approx(row.post_mean - q * row.post_sd, rel=1e-12)
    one_word = S.mixed_logit(df.assign(word="w"))
    assert one_word.term.tolist() == ["Intercept", "sd(participant_id)"]


def test_mixed_logit_refuses_separation_too_few_rows_and_too_many_levels():
    df = _crossed()
    split = df.assign(y=(df.writer == "robot").astype(float))
    sep = S.mixed_logit(split, "y", "pid", "item", fixed="writer").iloc[0]
    assert sep.status == (
        "failed: separation: every human answer is 0, so the fixed effects' log-odds are "
        "infinite (a fit would report its prior, not the data)"
    )
    assert sep.term == "(model)" and sep.type == "" and np.isnan(sep.post_mean)
    few = S.mixed_logit(df.iloc[:9], "y", "pid", "item").iloc[0]
    assert few.status == "failed: too few rows or clusters for a mixed model"
    assert len(S.mixed_logit(df.iloc[:10], "y", "pid", "item")) == 3  # 10 rows: fitted
    flat = S.mixed_logit(df.assign(pid="p", item="i"), "y", "pid", "item").iloc[0]
    assert flat.status == "failed: too few rows or clusters for a mixed model"
    big = S.mixed_logit(df, "y", "pid", "item", max_levels=37).iloc[0]
    assert big.status == (
        "skipped: 38 participants and words is more than the variational fit handles quickly "
        "(max_levels 37); the GEE results stand"
    )
    assert len(S.mixed_logit(df, "y", "pid", "item", max_levels=38)) == 3
    same = S.mixed_logit(df.assign(y=1.0), "y", "pid", "item").iloc[0]
    assert same.status == "failed: every answer is 1, so the log-odds are infinite"


def test_separated_cell_names_the_constant_cell_or_nothing():
    from patsy import dmatrix

    from studies.analysis.stats.mixed import _separated_cell

    df = _crossed().assign(_y=lambda f: f.y)
    design = dmatrix("writer", df, return_type="dataframe")
    assert _separated_cell(df, design, "writer") == ""
    df.loc[df.writer == "robot", "_y"] = 1.0
    assert _separated_cell(df, design, "writer") == "every robot answer is 1"
    ones = df.assign(_y=1.0)
    plain = dmatrix("1", ones, return_type="dataframe")
    assert _separated_cell(ones, plain, "1") == "every answer is 1"


# --------------------------------------------------------------------------- edges of the fit


def test_mixed_logit_default_level_cap_is_600_participants_and_words():
    # 591 participants + 10 words = 601 levels: skipped by default, before any fit
    rng = np.random.default_rng(3)
    df = pd.DataFrame(
        {
            "participant_id": np.arange(1182) // 2,
            "word": np.arange(1182) % 10,
            "chose_robot": (rng.random(1182) < 0.3).astype(float),
        }
    )
    row = S.mixed_logit(df).iloc[0]
    assert row.status.startswith("skipped: 601 participants and words")
    assert "(max_levels 600)" in row.status


def test_mixed_logit_keeps_rows_whose_other_columns_are_missing():
    df = _crossed().assign(note=np.nan)  # a free-text column nobody filled in
    out = S.mixed_logit(df, "y", "pid", "item").set_index("term")
    ref = S.mixed_logit(df.drop(columns="note"), "y", "pid", "item").set_index("term")
    np.testing.assert_allclose(out.post_mean, ref.post_mean, **VB)


def test_mixed_logit_says_when_the_optimiser_did_not_converge(monkeypatch):
    from statsmodels.genmod.bayes_mixed_glm import BinomialBayesMixedGLM

    fit_vb = BinomialBayesMixedGLM.fit_vb
    # a real fit stopped after one step: statsmodels warns "VB fitting did not converge"
    monkeypatch.setattr(
        BinomialBayesMixedGLM,
        "fit_vb",
        lambda self, **kwargs: fit_vb(self, minim_opts={"maxiter": 1}, **kwargs),
    )
    out = S.mixed_logit(_crossed(), "y", "pid", "item")
    warned = "converged with warnings (optimizer reported non-convergence); treat with caution"
    assert (out.status == warned).all()


def test_mixed_logit_other_warnings_leave_the_status_ok(monkeypatch):
    import warnings

    from statsmodels.genmod.bayes_mixed_glm import BinomialBayesMixedGLM

    fit_vb = BinomialBayesMixedGLM.fit_vb

    def noisy(self, **kwargs):
        warnings.warn("overflow encountered in exp", RuntimeWarning, stacklevel=2)
        return fit_vb(self, **kwargs)

    monkeypatch.setattr(BinomialBayesMixedGLM, "fit_vb", noisy)
    out = S.mixed_logit(_crossed(), "y", "pid", "item")
    assert out.status.str.startswith("ok (variational Bayes").all()


def test_mixed_logit_reads_the_first_rows_by_position_whatever_the_index():
    df = _crossed(writer=True)
    df.index = np.r_[np.arange(len(df) - 1), 0]  # a duplicated label, as after pd.concat
    split = df.assign(y=(df.writer == "robot").astype(float))
    sep = S.mixed_logit(split, "y", "pid", "item", fixed="writer").status.iloc[0]
    assert sep.startswith("failed: separation: every human answer is 0")


def test_separated_cell_names_the_first_constant_cell_in_the_data_and_every_named_column():
    from patsy import dmatrix

    from studies.analysis.stats.mixed import _separated_cell

    df = _crossed(writer=True).iloc[1:].reset_index(drop=True)  # the data start with a robot row
    df = df.assign(_y=(df.writer == "robot").astype(float))  # both cells constant
    design = dmatrix("writer", df, return_type="dataframe")
    assert _separated_cell(df, design, "writer") == "every robot answer is 1"
    # two factors named in the formula: both named, space-separated
    df["hand"] = "left"
    two = dmatrix("writer + hand", df, return_type="dataframe")
    assert _separated_cell(df, two, "writer + hand") == "every robot left answer is 1"
    # a cell of one row is enough, and a column ending in _y is named like any other
    one = pd.DataFrame({"writer_y": ["a", "b", "b", "a", "b"], "_y": [1.0, 0.0, 1.0, 0.0, 1.0]})
    one.loc[4, "writer_y"] = "c"
    design = dmatrix("writer_y", one, return_type="dataframe")
    assert _separated_cell(one, design, "writer_y") == "every c answer is 1"


def test_the_same_answers_give_the_same_mixed_model_to_the_last_digit():
    """statsmodels jitters the fit's starting point at random unless told where to start: two
    fits of one file must agree exactly, or a re-run report (and its DVC hash) moves."""
    df = _crossed(writer=True)
    first = S.mixed_logit(df, "y", "pid", "item", fixed="C(writer)")
    second = S.mixed_logit(df, "y", "pid", "item", fixed="C(writer)")
    pd.testing.assert_frame_equal(first, second, check_exact=True)
