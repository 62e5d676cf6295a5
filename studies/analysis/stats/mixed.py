"""The crossed random-effects logit (participants x words), fitted by variational Bayes."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pandas as pd
from scipy import stats

from studies.analysis.stats.common import expit, values

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

    frame = df.assign(_y=values(df, outcome)).dropna(subset=["_y"]).reset_index(drop=True)
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
            # statsmodels starts the standard deviations at exp(-0.5), each jittered at random
            # (unseeded): started without the jitter, the same answers give the same report
            start_sd = np.full(model.k_fep + model.k_vcp + model.k_vc, math.exp(-0.5))
            res = model.fit_vb(sd=start_sd)
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
        # vcp are log SDs: report the SD and its interval (no SD of an SD, no rate: NaN)
        rows.append(
            dict(
                term=f"sd({name})",
                type="random-effect SD (logit)",
                post_mean=float(np.exp(m)),
                ci_low=float(np.exp(m - q * s)),
                ci_high=float(np.exp(m + q * s)),
                status=status,
            )
        )
    return pd.DataFrame(rows, columns=list(MIXED_COLUMNS))


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
