"""Run every analysis of a study on checked responses; collect tidy tables and conclusions.

:func:`analyze_turing` and :func:`analyze_readability` take the analysed rows (a long frame)
and the options, and return a :class:`StudyAnalysis`: the tidy tables that become
``tests.csv``, ``per_word.csv`` and ``per_participant.csv``, the mixed-model terms, the
plain-language conclusions and a machine-readable ``verdict``. :func:`analyze_file` reads and
checks a responses CSV first (:mod:`studies.analysis.validate`) and analyses each study in it.

Primary analyses (what the conclusions rest on): study 1, H1 — GEE on participants (rate vs
chance, and TOST of ``chance ± margin``); H2 — t-test on participant mean confidence
(two-sided). Study 2 — paired tests on participants' success rates (difference, TOST,
non-inferiority). The paper-faithful tests and the other recommended ones are reported beside
them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from prg.errors import UsageError
from studies.analysis import stats as S
from studies.analysis.config import AnalysisSettings
from studies.analysis.schema import READABILITY, TURING
from studies.analysis.stats import format_p
from studies.analysis.stats.common import decision, result_frame
from studies.analysis.validate import (
    Responses,
    analysis_rows,
    attention_summary,
    check_responses,
    load_responses,
)

if TYPE_CHECKING:
    from studies.analysis.participants import Truth

PAPER = "paper-faithful"
RECOMMENDED = "recommended"


@dataclass
class StudyAnalysis:
    """The results of one study (see the module docstring)."""

    kind: str
    margin: float
    config: AnalysisSettings
    data: pd.DataFrame
    tests: pd.DataFrame
    per_word: pd.DataFrame
    per_participant: pd.DataFrame
    mixed: pd.DataFrame
    icc: pd.DataFrame
    conclusions: list[str]
    verdict: dict
    warnings: list[str] = field(default_factory=list)
    contrasts: list[str] = field(default_factory=list)
    truth: Truth | None = None  #: simulated: what the participants were drawn from
    truth_path: str | None = None  #: where it was read (see studies.analysis.truth.with_truth)


@dataclass
class Analysis:
    """A whole responses file analysed; ``origin`` says whose answers they are (``study``,
    ``pilot`` or ``simulated``, see :data:`studies.analysis.schema.ORIGINS`)."""

    source: str
    config: AnalysisSettings
    notes: list[str]
    attention: pd.DataFrame
    rows_in_file: int
    studies: list[StudyAnalysis]
    origin: str = "study"


def _tag(frame: pd.DataFrame, kind: str, approach: str, hypothesis: str) -> pd.DataFrame:
    out = frame.copy()
    out.insert(0, "hypothesis", hypothesis)
    out.insert(0, "approach", approach)
    out.insert(0, "study", kind)
    return out


def _row(tests: pd.DataFrame, name: str) -> pd.Series | None:
    hit = tests[tests["test"] == name]
    return hit.iloc[0] if len(hit) else None


def _ok(row: pd.Series | None) -> bool:
    return row is not None and np.isfinite(row["p_value"])


def _rejected(row: pd.Series | None) -> bool:
    """The test ``row`` was run and rejected its null hypothesis."""
    return bool(_ok(row) and row["reject"])


def _ci_bounds(row: pd.Series) -> list[float]:
    return [float(row["ci_low"]), float(row["ci_high"])]


def _ci(row: pd.Series, digits: int = 3) -> str:
    return f"{row['estimate']:.{digits}f} (95 % CI {row['ci_low']:.{digits}f} to {row['ci_high']:.{digits}f})"


def _mixed_test(
    data: pd.DataFrame, a: float, z: float, shown: str, not_shown: str, **fields
) -> pd.DataFrame:
    """A result row for a term of the crossed mixed logit: the two-sided normal test of its
    posterior ``z`` (``shown`` or ``not_shown`` in the conclusion, with the p value)."""
    from scipy import stats as st

    p = float(2 * st.norm.sf(abs(z)))
    return result_frame(
        n=len(data),
        clusters=data["participant_id"].nunique(),
        ci_level=1 - a,
        statistic=z,
        alpha=a,
        **decision(p, a, shown, not_shown),
        **fields,
    )


def _mixed_term(
    data: pd.DataFrame, cfg: AnalysisSettings, outcome: str, fixed: str, term: int
) -> tuple[pd.DataFrame, pd.Series | None]:
    """The crossed mixed logit of ``outcome`` on ``fixed`` (an empty frame when ``cfg`` turns it
    off) and its row ``term`` (0: the intercept), None unless the fit succeeded and has that row."""
    if not cfg.mixed_model:
        return pd.DataFrame(), None
    mixed = S.mixed_logit(data, outcome, "participant_id", "word", fixed, cfg.alpha)
    fitted = len(mixed) > term and mixed["status"].iloc[0].startswith(("ok", "converged"))
    return mixed, mixed.iloc[term] if fitted else None


def _study_analysis(
    kind: str,
    cfg: AnalysisSettings,
    data: pd.DataFrame,
    tests: pd.DataFrame,
    mixed: pd.DataFrame,
    tables: tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame],
    candidates: dict[str, float],
    judged: tuple[dict, list[str], list[str]],
) -> StudyAnalysis:
    """A study's results: ``tables`` (per word, per participant, ICC) get a ``study`` column
    first; the margin's warnings weigh it against ``candidates`` (quantities of the data it may
    have been taken from); ``judged`` is the study's (verdict, conclusions, contrasts)."""
    for table in tables:
        table.insert(0, "study", kind)
    per_word, per_part, icc = tables
    margin = cfg.margin_for(kind)
    warnings = S.margin_warnings(margin, cfg.margin_source, candidates)
    verdict, conclusions, contrasts = judged
    return StudyAnalysis(
        kind,
        margin,
        cfg,
        data,
        tests,
        per_word,
        per_part,
        mixed,
        icc,
        conclusions,
        verdict,
        warnings,
        contrasts,
    )


def analyze_turing(data: pd.DataFrame, cfg: AnalysisSettings) -> StudyAnalysis:
    """Study 1: H1 (can participants pick the robot's sample above chance?) and H2 (confidence).

    Parameters
    ----------
    data : DataFrame
        Analysed rows: participant_id, word, chose_robot (0/1), confidence (1-5).
    cfg : AnalysisSettings
        chance, margin, alpha, neutral, margin_source, mixed_model.
    """
    c, a, margin = cfg.chance, cfg.alpha, cfg.margin_for(TURING)
    neutral = cfg.neutral
    h1, h2 = "H1: indistinguishable from chance", "H2: confidence not high"
    parts = [
        _tag(frame, TURING, approach, hypothesis)
        for approach, hypothesis, frame in (
            (PAPER, h1, S.binomial_test(data, "chose_robot", c, "greater", a)),
            (PAPER, h1, S.binomial_tost(data, "chose_robot", c, margin, a)),
            (PAPER, h2, S.one_sample_ttest(data, "confidence", neutral, "greater", a)),
            (RECOMMENDED, h1, S.gee_rate(data, "chose_robot", "participant_id", c, margin, a)),
            (
                RECOMMENDED,
                h2,
                S.one_sample_ttest(
                    data, "confidence", neutral, "two-sided", a, cluster="participant_id"
                ),
            ),
            (RECOMMENDED, h2, S.signed_rank_test(data, "confidence", neutral, "participant_id", a)),
        )
    ]
    # cluster-level check on H1: participants' rates, one value each
    rates = S.rates_by(data, "chose_robot", "participant_id", a)
    prate = rates.rename(columns={"rate": "_r"})[["participant_id", "_r"]]
    parts.append(
        _tag(
            S.one_sample_ttest(prate, "_r", c, "two-sided", a, cluster="participant_id").assign(
                test=f"one-sample t-test vs {c:g} on participant rates"
            ),
            TURING,
            RECOMMENDED,
            h1,
        )
    )
    mixed, icept = _mixed_term(data, cfg, "chose_robot", "1", term=0)
    if icept is not None:
        z = (icept.post_mean - S.logit(c)) / icept.post_sd
        test = _mixed_test(
            data,
            a,
            z,
            shown=f"{'above' if z > 0 else 'below'} chance",
            not_shown="not shown to differ from chance",
            test="crossed mixed logit vs chance (typical participant and word)",
            null_hypothesis=f"rate = {c:g}",
            estimate=icept.rate,
            ci_low=icept.rate_low,
            ci_high=icept.rate_high,
            method="BinomialBayesMixedGLM.fit_vb, random intercepts for participants and words; "
            "approximate posterior (variational Bayes); conditional, not population-average, rate",
        )
        parts.append(_tag(test, TURING, RECOMMENDED, h1))
    tests = pd.concat(parts, ignore_index=True)

    per_word = S.rates_by(data, "chose_robot", "word", a, chance=c)
    conf_w = data.groupby("word")["confidence"].mean().rename("mean_confidence")
    per_word = per_word.merge(conf_w, on="word", how="left")
    conf_p = data.groupby("participant_id")["confidence"].agg(
        mean_confidence="mean", sd_confidence="std"
    )
    per_part = rates.merge(conf_p, on="participant_id", how="left")
    icc = pd.concat(
        [S.icc_oneway(data, "chose_robot"), S.icc_oneway(data, "confidence")], ignore_index=True
    )
    candidates = S.margin_candidates(data, "chose_robot", "word", a)
    judged = _turing_verdict(tests, c, margin, neutral, a)
    return _study_analysis(
        TURING, cfg, data, tests, mixed, (per_word, per_part, icc), candidates, judged
    )


def _turing_verdict(tests: pd.DataFrame, c: float, margin: float, neutral: float, a: float):
    gee = _row(tests, "GEE rate vs chance")
    gee_tost = _row(tests, "GEE TOST vs chance")
    fallback = _row(tests, f"one-sample t-test vs {c:g} on participant rates")
    primary = gee if _ok(gee) else fallback
    verdict: dict = {"study": TURING, "chance": c, "margin": margin, "alpha": a}
    lines, contrasts = [], []
    if _ok(primary):
        est = float(primary["estimate"])
        above = bool(primary["reject"] and est > c)
        below = bool(primary["reject"] and est < c)
        equiv = _rejected(gee_tost) if primary is gee else False
        if equiv and not (above or below):
            h1 = "equivalent to chance"
        elif equiv:
            h1 = f"equivalent to chance (a small difference, within ±{margin:g})"
        elif above:
            h1 = "above chance"
        elif below:
            h1 = "below chance"
        else:
            h1 = "inconclusive"
        verdict.update(
            h1=h1,
            h1_equivalent=equiv,
            above_chance=above,
            below_chance=below,
            rate=est,
            rate_ci=_ci_bounds(primary),
            h1_primary=primary["test"],
        )
        how = "GEE on participants" if primary is gee else "participant rates"
        text = {
            "equivalent to chance": f"**H1 supported**: participants picked the robot's sample at {_ci(primary)}, "
            f"equivalent to chance {c:g} within ±{margin:g} ({how}; TOST {format_p(gee_tost['p_value']) if _ok(gee_tost) else ''}).",
            "above chance": f"**H1 not supported**: participants picked the robot's sample at {_ci(primary)}, "
            f"above chance {c:g} ({how}, {format_p(primary['p_value'])}): they can tell the robot's writing apart.",
            "below chance": f"**H1 not supported as stated**: participants picked the robot's sample at {_ci(primary)}, "
            f"*below* chance {c:g} ({how}, {format_p(primary['p_value'])}): they took the robot's writing for a human's more often than a human's.",
            "inconclusive": f"**H1 undecided**: the rate of picking the robot's sample, {_ci(primary)}, neither differs "
            f"from chance {c:g} nor is shown equivalent within ±{margin:g} ({how}); more data are needed.",
        }.get(h1, f"**H1**: {h1}: rate {_ci(primary)} ({how}).")
        lines.append(text)
        paper_tost = _row(tests, "exact binomial TOST vs chance")
        if (
            paper_tost is not None
            and _ok(gee_tost)
            and bool(paper_tost["reject"]) != bool(gee_tost["reject"])
        ):
            contrasts.append(
                f"The exact binomial TOST that treats all trials as independent "
                f"{'shows' if paper_tost['reject'] else 'does not show'} equivalence ({format_p(paper_tost['p_value'])}); "
                f"allowing for participants (GEE) it {'does' if gee_tost['reject'] else 'does not'} "
                f"({format_p(gee_tost['p_value'])})."
            )
    else:
        why = _reasons(gee, fallback)
        exact = _row(tests, "exact binomial test vs chance")
        seen = (
            f" Observed rate {_ci(exact)} (exact interval; trials treated as independent)."
            if exact is not None and np.isfinite(exact["estimate"])
            else ""
        )
        verdict.update(h1="not estimable", h1_reason=why)
        lines.append(f"**H1**: not estimable from these data: {why}.{seen}")
    h2p = _row(tests, f"one-sample t-test vs {neutral:g} on participant means")
    if _ok(h2p):
        m = float(h2p["estimate"])
        if h2p["reject"]:
            h2 = "above neutral" if m > neutral else "below neutral"
        else:
            h2 = "not different from neutral"
        verdict.update(h2=h2, confidence_mean=m, confidence_ci=_ci_bounds(h2p))
        lines.append(
            {
                "above neutral": f"**H2 not supported**: mean confidence (participant means) {_ci(h2p, 2)} is above neutral {neutral:g} ({format_p(h2p['p_value'])}).",
                "below neutral": f"**H2 supported**: mean confidence (participant means) {_ci(h2p, 2)} is below neutral {neutral:g} ({format_p(h2p['p_value'])}).",
                "not different from neutral": f"**H2 undecided**: mean confidence (participant means) {_ci(h2p, 2)} is not shown to differ from neutral {neutral:g} ({format_p(h2p['p_value'])}).",
            }[h2]
        )
        paper_h2 = _row(tests, f"one-sample t-test vs {neutral:g} on ratings")
        if paper_h2 is not None and _ok(paper_h2):
            same = bool(paper_h2["reject"]) == bool(h2p["reject"] and m > neutral)
            if not same:
                contrasts.append(
                    f"The paper's H2 test on all ratings as independent gives {format_p(paper_h2['p_value'])} "
                    f"(one-sided, 'mean <= {neutral:g}'); on participant means the evidence is "
                    f"{format_p(h2p['p_value'])} (two-sided): the conclusions differ."
                )
    else:
        why = _reasons(h2p)
        verdict.update(h2="not estimable", h2_reason=why)
        rank = _row(tests, f"Wilcoxon signed-rank vs {neutral:g} on participant means")
        lines.append(
            f"**H2**: not estimable by the t-test on participant means: {why}."
            + (
                f" The signed-rank test on the same means: {rank['conclusion']}."
                if _ok(rank)
                else ""
            )
        )
    return verdict, lines, contrasts


def _reasons(*rows: pd.Series | None) -> str:
    """Why the tests in ``rows`` could not be run, from their conclusions (``not estimable: ...``)."""
    out = []
    for r in rows:
        if r is None:
            continue
        text = str(r["conclusion"]) if isinstance(r["conclusion"], str) else "no result"
        text = text.removeprefix("not estimable: ")
        item = f"{r['test']}: {text}"
        if item not in out:
            out.append(item)
    return "; ".join(out) or "no test could be run"


def analyze_readability(data: pd.DataFrame, cfg: AnalysisSettings) -> StudyAnalysis:
    """Study 2: is the robot's writing as readable as the human's?

    Parameters
    ----------
    data : DataFrame
        Analysed rows: participant_id, word, writer (human/robot), correct (0/1).
    cfg : AnalysisSettings
        margin, alpha, margin_source, mixed_model.
    """
    a, margin = cfg.alpha, cfg.margin_for(READABILITY)
    hyp = "robot's words as readable as the human's"
    levels = ("human", "robot")
    parts = [
        _tag(frame, READABILITY, approach, hyp)
        for approach, frame in (
            (PAPER, S.group_ttest(data, "correct", "writer", "word", levels, a)),
            (
                RECOMMENDED,
                S.paired_tests(data, "correct", "writer", "participant_id", levels, margin, a),
            ),
            (
                RECOMMENDED,
                S.gee_difference(data, "correct", "writer", "participant_id", levels, margin, a),
            ),
            (RECOMMENDED, S.paired_tests(data, "correct", "writer", "word", levels, margin, a)),
        )
    ]
    mixed, eff = _mixed_term(data, cfg, "correct", "C(writer, Treatment('human'))", term=1)
    if eff is not None:
        z = eff.post_mean / eff.post_sd
        test = _mixed_test(
            data,
            a,
            z,
            shown=f"robot {'more' if z > 0 else 'less'} readable",
            not_shown="difference not shown",
            test="crossed mixed logit: writer effect (robot vs human, log-odds)",
            null_hypothesis="log-odds ratio = 0",
            estimate=eff.post_mean,
            ci_low=eff.ci_low,
            ci_high=eff.ci_high,
            method="BinomialBayesMixedGLM.fit_vb, random intercepts for participants and words; approximate posterior",
        )
        parts.append(_tag(test, READABILITY, RECOMMENDED, hyp))
    tests = pd.concat(parts, ignore_index=True)

    per_word = S.rates_by(data, "correct", ["word", "writer"], a)
    pw = S.rates_by(data, "correct", ["participant_id", "writer"], a)
    wide = pw.pivot_table(index="participant_id", columns="writer", values=["n", "rate"])
    per_part = pd.DataFrame(index=wide.index)
    for w in ("human", "robot"):
        if ("rate", w) in wide:
            per_part[f"n_{w}"] = wide[("n", w)]
            per_part[f"rate_{w}"] = wide[("rate", w)]
    if {"rate_human", "rate_robot"} <= set(per_part.columns):
        per_part["difference"] = per_part["rate_robot"] - per_part["rate_human"]
    overall = S.rates_by(data, "correct", "participant_id", a)
    per_part = overall.merge(per_part.reset_index(), on="participant_id", how="left")
    if "list_id" in data:
        per_part = per_part.merge(
            data.groupby("participant_id")["list_id"].first(), on="participant_id", how="left"
        )
    icc = S.icc_oneway(data, "correct")
    diff = _row(tests, "paired t-test by participant (robot - human)")
    candidates = {}
    if _ok(diff):
        candidates = {
            "the CI half-width of the difference": float(diff["ci_high"] - diff["estimate"]),
            "the observed difference": abs(float(diff["estimate"])),
        }
    judged = _readability_verdict(tests, margin, a, S.rates_by(data, "correct", "writer", a))
    return _study_analysis(
        READABILITY, cfg, data, tests, mixed, (per_word, per_part, icc), candidates, judged
    )


def _readability_verdict(
    tests: pd.DataFrame, margin: float, a: float, rates: pd.DataFrame | None = None
):
    diff = _row(tests, "paired t-test by participant (robot - human)")
    tost = _row(tests, f"paired TOST by participant (±{margin:g})")
    ni = _row(tests, f"non-inferiority by participant (margin {margin:g})")
    verdict: dict = {"study": READABILITY, "margin": margin, "alpha": a}
    lines, contrasts = [], []
    how = "paired by participant"
    if not _ok(diff):  # e.g. a between-participants file: fall back on the GEE
        paired = diff
        diff = _row(tests, "GEE difference (robot - human)")
        tost = _row(tests, f"GEE TOST (±{margin:g})")
        ni = _row(tests, f"GEE non-inferiority (margin {margin:g})")
        how = f"GEE on participants; the paired tests are not estimable ({_reasons(paired)})"
        if not _ok(diff):
            why = _reasons(paired, diff)
            verdict.update(verdict="not estimable", reason=why)
            seen = ""
            if rates is not None and len(rates):
                seen = (
                    " Observed success rates: "
                    + ", ".join(
                        f"{r.writer} {r.rate:.3f} ({1 - a:.0%} Wilson CI {r.ci_low:.3f} to {r.ci_high:.3f})"
                        for r in rates.itertuples(index=False)
                    )
                    + "."
                )
            lines.append(f"**Readability**: not estimable from these data: {why}.{seen}")
            return verdict, lines, contrasts
    d = float(diff["estimate"])
    equiv = _rejected(tost)
    noninf = _rejected(ni)
    sig = bool(diff["reject"])
    if equiv:
        v = "equally readable"
    elif sig:
        v = "robot more readable" if d > 0 else "robot less readable"
    elif noninf:
        v = "non-inferior"
    else:
        v = "inconclusive"
    verdict.update(
        verdict=v,
        equivalent=equiv,
        noninferior=noninf,
        different=sig,
        difference=d,
        difference_ci=_ci_bounds(diff),
        primary=diff["test"],
    )
    head = f"robot minus human success rate {_ci(diff)} ({how})"
    lines.append(
        {
            "equally readable": f"**Equally readable**: {head}; equivalence within ±{margin:g} shown (TOST {format_p(tost['p_value'])}).",
            "robot more readable": f"**The robot's words are more readable**: {head}, {format_p(diff['p_value'])}.",
            "robot less readable": f"**The robot's words are less readable**: {head}, {format_p(diff['p_value'])}"
            + (
                f"; still non-inferior at −{margin:g} ({format_p(ni['p_value'])})."
                if noninf
                else f"; non-inferiority at −{margin:g} not shown."
            ),
            "non-inferior": f"**Non-inferior, equivalence not shown**: {head}; the robot is not worse by {margin:g} or more "
            f"(non-inferiority {format_p(ni['p_value'])}), but equivalence within ±{margin:g} is not shown (TOST {format_p(tost['p_value'])}).",
            "inconclusive": f"**Undecided**: {head}; neither a difference ({format_p(diff['p_value'])}), equivalence (TOST "
            f"{format_p(tost['p_value'])}) nor non-inferiority ({format_p(ni['p_value'])}) is shown.",
        }[v]
    )
    paper = _row(tests, "independent t-test on word rates (robot - human)")
    if _ok(paper) and not paper["reject"] and not equiv:
        contrasts.append(
            f"The paper's independent t-test on word rates does not reject 'no difference' ({format_p(paper['p_value'])}); "
            f"read as the paper did, that would 'accept' equality, but equivalence within ±{margin:g} is not shown here."
        )
    return verdict, lines, contrasts


def analyze_file(path: str, cfg: AnalysisSettings) -> Analysis:
    """Read, check and analyse a responses CSV (every study it holds, or ``cfg.kind`` only)."""
    return _analyze(load_responses(path, kind=cfg.kind, n_options=cfg.n_options), cfg)


def analyze_table(table: pd.DataFrame, cfg: AnalysisSettings, name: str = "responses") -> Analysis:
    """Check and analyse a responses table in memory (e.g. straight from the simulator)."""
    return _analyze(check_responses(table, name, kind=cfg.kind, n_options=cfg.n_options), cfg)


def _analyze(resp: Responses, cfg: AnalysisSettings) -> Analysis:
    notes = list(cfg.notes) + list(resp.notes)
    studies = []
    att = attention_summary(resp.frame)
    for kind in resp.kinds:
        if (
            kind == TURING
            and not 0
            < cfg.chance - cfg.margin_for(TURING)
            < cfg.chance + cfg.margin_for(TURING)
            < 1
        ):
            raise UsageError(
                f"chance {cfg.chance:g} ± the turing equivalence margin {cfg.margin_for(TURING):g} "
                "must stay inside (0, 1): the margin (--margin or the study's equivalence_margin) "
                "must be below both chance (--chance) and 1 - chance"
            )
        frame = resp.frame[resp.frame["study"] == kind]
        used, ex_notes = analysis_rows(
            frame,
            include_attention_rows=cfg.include_attention_rows,
            exclude_failed=cfg.exclude_failed_attention,
        )
        notes += [f"{kind}: {n}" for n in ex_notes]
        if used.empty:
            raise UsageError(f"{resp.path}: no {kind} rows left to analyse after exclusions")
        fn = analyze_turing if kind == TURING else analyze_readability
        studies.append(fn(used, cfg))
    return Analysis(resp.path, cfg, notes, att, len(resp.frame), studies, resp.origin)
