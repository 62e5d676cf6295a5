"""The report's sections on each study: study 1 (Turing-like test) and study 2 (readability),
their tests, figures, per-word tables and the crossed mixed logit."""

from __future__ import annotations

import numpy as np
import pandas as pd

from studies.analysis.analyze import StudyAnalysis
from studies.analysis.report.document import Doc
from studies.analysis.report.figures import (
    _png,
    fig_confidence,
    fig_differences,
    fig_readability,
    fig_turing_participants,
    fig_turing_words,
)
from studies.analysis.report.formatting import _num, fmt_p, tests_table


def _row(tests: pd.DataFrame, name: str):
    hit = tests[tests["test"] == name]
    return hit.iloc[0] if len(hit) else None


def _truth_column(frame: pd.DataFrame) -> list[str]:
    """``["truth"]`` when ``frame`` has the simulation's truth beside its estimates, else ``[]``."""
    return ["truth"] if "truth" in frame else []


def _interval(tests: pd.DataFrame, name: str) -> tuple[float, float, float] | None:
    """(estimate, ci_low, ci_high) of the test ``name``; None when it is missing or not estimated."""
    row = _row(tests, name)
    if row is None or not np.isfinite(row.estimate):
        return None
    return row.estimate, row.ci_low, row.ci_high


def _study1_section(doc: Doc, st: StudyAnalysis) -> None:
    cfg, c, m, truth = st.config, st.config.chance, st.margin, st.truth
    d = st.data
    doc.h(2, "Study 1: Turing-like test")
    doc.p(
        f"{d['participant_id'].nunique()} participants, {d['word'].nunique()} words, {len(d)} trials. On each trial a "
        f"participant saw {cfg.n_options} samples of a word (one by the robot) and picked the one they thought the robot "
        f"wrote, then rated their confidence 1-5. Guessing picks the robot with probability {c:g}. "
        f"**H1** (indistinguishable): the rate is within {c:g} ± {m:g}. **H2** (low confidence): mean confidence is not "
        f"above neutral ({cfg.neutral:g})."
    )
    for w in st.warnings:
        doc.warn(w)
    doc.h(3, "H1: can participants tell the robot's writing apart?")
    h1 = st.tests[st.tests["hypothesis"].str.startswith("H1")]
    doc.table(
        tests_table(h1),
        "Tests of H1. Paper-faithful rows treat all trials as independent; recommended rows allow for participants.",
    )
    overall = _interval(st.tests, "GEE rate vs chance")
    doc.figure(
        "turing_per_word.png",
        _png(fig_turing_words(st.per_word, c, m, overall, truth and truth.rate)),
        "Rate of picking the robot's sample per word (95 % Wilson CIs, trials independent within a word); "
        "green: chance and the equivalence band; blue: the overall GEE estimate and its 95 % CI.",
    )
    columns = ["word", "n", "k", "rate", "ci_low", "ci_high", "p_vs_chance", "p_holm"]
    pw = st.per_word[[*columns, *_truth_column(st.per_word), "mean_confidence"]].copy()
    for col in ("rate", "ci_low", "ci_high", *_truth_column(st.per_word)):
        pw[col] = pw[col].map(_num)
    pw["p_vs_chance"] = pw["p_vs_chance"].map(fmt_p)
    pw["p_holm"] = pw["p_holm"].map(fmt_p)
    pw["mean_confidence"] = pw["mean_confidence"].map(lambda x: _num(x, 2))
    doc.table(
        pw,
        "Per word: robot picks k of n, rate with 95 % Wilson CI, exact two-sided binomial test vs chance (Holm-adjusted over words).",
    )
    icc = st.icc.set_index("value")
    if "chose_robot" in icc.index and not np.isfinite(icc.loc["chose_robot"].icc):
        doc.p(
            "The ICC of the 0/1 answers is not estimable from these data (every answer the same, "
            "or fewer than 2 participants), so neither is the design effect."
        )
    elif "chose_robot" in icc.index:
        r = icc.loc["chose_robot"]
        doc.p(
            f"Answers cluster within participants: the ICC of the 0/1 answers is {_num(r.icc)} "
            f"(design effect {_num(r.design_effect, 2)} for {r.mean_cluster_size:.3g} trials per participant), "
            f"so {len(d)} trials carry the information of about {len(d) / max(r.design_effect, 1):.0f} independent ones."
        )
    doc.figure(
        "turing_participants.png",
        _png(fig_turing_participants(st.per_participant, c)),
        "Participants' own rates of picking the robot's sample.",
    )
    doc.h(3, "Crossed mixed logit (sensitivity analysis)")
    _mixed(doc, st.mixed, "rate of a typical participant on a typical word")
    doc.h(3, "H2: how confident were participants?")
    h2 = st.tests[st.tests["hypothesis"].str.startswith("H2")]
    doc.table(tests_table(h2, 2), "Tests of H2 against the neutral rating.")
    if "confidence" in icc.index:
        r = icc.loc["confidence"]
        doc.p(
            f"Ratings cluster within participants (ICC {_num(r.icc)}, design effect {_num(r.design_effect, 2)}): the "
            "paper-faithful test's n counts every rating as a separate person; the recommended test uses one mean per "
            "participant. Ratings are ordinal, so a signed-rank test on the participant means is shown as a check."
        )
    doc.figure(
        "turing_confidence.png",
        _png(fig_confidence(d, cfg.neutral, truth and truth.confidence_mean)),
        "Left: confidence ratings split by whether the robot's sample was picked. Right: participants' mean confidence.",
    )


def _mixed(doc: Doc, mixed: pd.DataFrame, what: str) -> None:
    if mixed is None or mixed.empty:
        doc.p("The crossed mixed logit was not fitted (`--no-mixed`).")
        return
    status = str(mixed["status"].iloc[0])
    if status.startswith("skipped"):
        doc.p(f"The crossed mixed logit was skipped: {status[len('skipped: ') :]}.")
        return
    if status.startswith("failed"):
        doc.warn(
            f"The crossed mixed logit (participants x words) could not be fitted: {status[len('failed: ') :]}. "
            "The GEE results above do not depend on it."
        )
        return
    t = mixed.copy()
    view = pd.DataFrame(
        {
            "term": t["term"],
            "type": t["type"],
            "posterior mean": t["post_mean"].map(_num),
            **({"truth": t["truth"].map(_num)} if "truth" in t else {}),
            "95 % interval": [f"[{_num(a)}, {_num(b)}]" for a, b in zip(t["ci_low"], t["ci_high"])],
            "as a rate": [
                f"{_num(r)} [{_num(a)}, {_num(b)}]" if np.isfinite(r) else ""
                for r, a, b in zip(t["rate"], t["rate_low"], t["rate_high"])
            ],
        }
    )
    doc.table(
        view,
        "Crossed random intercepts for participants and words (BinomialBayesMixedGLM, variational Bayes).",
    )
    doc.p(
        f"*Caveat*: this model is fitted by mean-field variational Bayes (statsmodels' `BinomialBayesMixedGLM.fit_vb`, "
        f"priors N(0, 2²) on fixed effects and N(0, 1) on log random-effect SDs). Its intervals are approximate and "
        f"typically too narrow, and its intercept is the {what}, not the population-average rate the GEE estimates. "
        f"It is shown because it is the one analysis here that allows for word-to-word variation as well as "
        f"participants; status: {status}."
    )


def _study2_section(doc: Doc, st: StudyAnalysis) -> None:
    m, truth = st.margin, st.truth
    d = st.data
    doc.h(2, "Study 2: readability")
    lists = d["list_id"].replace("", np.nan).dropna().unique() if "list_id" in d else []
    doc.p(
        f"{d['participant_id'].nunique()} participants typed the word they saw; {len(d)} trials over "
        f"{d['word'].nunique()} words, each participant reading words by both writers"
        + (
            f" (lists {', '.join(map(str, sorted(lists)))} swap who wrote which word)"
            if len(lists)
            else ""
        )
        + f". The question is whether the robot's words are as readable as the human's: equivalence within ±{m:g} "
        f"(TOST), or at least non-inferiority (robot ≥ human − {m:g})."
    )
    for w in st.warnings:
        doc.warn(w)
    doc.table(
        tests_table(st.tests),
        "Tests of readability (robot minus human). The paper-faithful test ignores the pairing.",
    )
    doc.figure(
        "readability_per_writer.png",
        _png(
            fig_readability(
                st.per_word,
                d,
                truth and {"human": truth.human_rate, "robot": truth.robot_rate},
            )
        ),
        "Left: success rate per writer (95 % Wilson CI), dots are participants. Right: each word's success rate in both writings.",
    )
    diff = _interval(st.tests, f"paired TOST by participant (±{m:g})")
    doc.figure(
        "readability_differences.png",
        _png(
            fig_differences(
                st.per_participant, m, diff, truth and truth.robot_rate - truth.human_rate
            )
        ),
        f"Participants' robot-minus-human differences; equivalence needs the 90 % CI inside ±{m:g}.",
    )
    pw = st.per_word.copy()
    for col in ("rate", "ci_low", "ci_high", *_truth_column(pw)):
        pw[col] = pw[col].map(_num)
    doc.table(
        pw[["word", "writer", "n", "k", "rate", "ci_low", "ci_high", *_truth_column(pw)]],
        "Per word and writer: k of n typed correctly, rate with 95 % Wilson CI.",
    )
    doc.h(3, "Crossed mixed logit (sensitivity analysis)")
    _mixed(
        doc,
        st.mixed,
        "log-odds of a typical participant on a typical word (the writer term is the robot-vs-human log-odds ratio)",
    )
