"""The report as a :class:`~studies.analysis.report.document.Doc`: the summary, the data, each
study's section, the paper's weaknesses, the methods and (optionally) the automatic judge."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from studies.analysis.analyze import Analysis
from studies.analysis.report.document import Doc
from studies.analysis.report.sections import _study1_section, _study2_section
from studies.analysis.schema import TURING


def _paper_section(doc: Doc, reproduced: pd.DataFrame | None, analysis: Analysis) -> None:
    from studies.analysis.paper import WEAKNESSES

    doc.h(2, "Where the paper's analysis was weak")
    doc.p(
        'The paper ("User Study on PRG against Human Calligraphy") reports summary numbers only. Re-running its tests '
        "from those numbers reproduces its conclusions, and shows where the analysis falls short:"
    )
    doc.ul([f"**{head}** {body}" for head, body in WEAKNESSES])
    contrasts = [c for st in analysis.studies for c in st.contrasts]
    if contrasts:
        doc.p(
            "On the data analysed in this report, the paper's way of testing and the recommended one disagree:"
        )
        doc.ul(contrasts)
    if reproduced is not None:
        view = reproduced[["study", "quantity", "shown", "expected", "note"]].rename(
            columns={"shown": "reproduced", "expected": "re-analysis (studies.md)"}
        )
        doc.table(
            view,
            "The paper's numbers reproduced from its summaries (data rebuilt to match them; see studies.analysis.paper).",
        )


def _methods(doc: Doc, analysis: Analysis) -> None:
    import scipy
    import statsmodels

    cfg = analysis.config
    doc.h(2, "Methods")
    doc.ul(
        [
            "**Paper-faithful**: exact binomial test of the robot-pick rate against chance (one-sided), exact binomial "
            "TOST on chance ± margin, one-sided t-test of all confidence ratings against neutral, and (study 2) an "
            "independent two-sample t-test on the words' success rates. All treat trials as independent.",
            "**GEE**: logit link with offset logit(chance), exchangeable working correlation within participants, "
            "bias-reduced (Mancl-DeRouen) sandwich standard errors; TOST on the logit scale against "
            "logit(chance ± margin). Study 2: identity link for the robot-minus-human difference.",
            "**Participant-level tests**: one value per participant (mean confidence; rate; robot-minus-human "
            "difference) in one-sample or paired t-tests (`scipy.stats`), the paired TOST with "
            "`statsmodels.stats.weightstats.ttost_paired`, non-inferiority as a one-sided paired t-test against −margin. "
            "By-word paired tests treat words as the unit instead.",
            "**Crossed mixed logit**: random intercepts for participants and words, `BinomialBayesMixedGLM.fit_vb`.",
            "**Equivalence**: shown when both one-sided nulls are rejected at alpha, i.e. when the 1 − 2·alpha CI lies "
            "inside the margin. Not rejecting 'no difference' is never read as equality.",
            f"**Options**: chance {cfg.chance:g}, alpha {cfg.alpha:g}, margin source {cfg.margin_source}"
            + (f", config {cfg.source}" if cfg.source else "")
            + f"; attention-check rows {'included' if cfg.include_attention_rows else 'excluded'}; participants failing "
            f"an attention check {'excluded' if cfg.exclude_failed_attention else 'kept'}.",
            f"Software: scipy {scipy.__version__}, statsmodels {statsmodels.__version__}.",
        ]
    )
    doc.p(
        "Files: `tests.csv` (one row per test), `per_word.csv`, `per_participant.csv`, `mixed_model.csv`, "
        "`paper_reproduction.csv`, `metrics.json` (the verdicts), `figures/`."
    )


ORIGIN_TITLES = {"simulated": " — SIMULATED participants", "pilot": " — PILOT data"}


def _origin_banner(doc: Doc, analysis: Analysis) -> None:
    """Say first that the answers are not people's answers to the study, when they are not."""
    if analysis.origin == "pilot":
        doc.banner(
            "PILOT DATA",
            "These answers were recorded by a pilot build of the study pages (human samples "
            "stood in for by copies of the robot's writing): they try out the pages and the "
            "analysis and say nothing about the robot's handwriting.",
        )
    elif analysis.origin == "simulated":
        from studies.analysis.truth import describe

        known = [
            f"{st.kind}: {describe(st.truth)} (`{st.truth_path}`)"
            for st in analysis.studies
            if st.truth is not None
        ]
        missing = [st.kind for st in analysis.studies if st.truth is None]
        drawn = "drawn by `prg-study simulate`"
        if known:
            drawn += (
                f" from a known truth ({'; '.join(known)}); each estimate below is shown "
                "beside the true value it should recover."
            )
        if missing:
            drawn += (
                f"{' The' if known else '; the'} truth of {', '.join(missing)} (its "
                "`<name>.truth.json`, or `--truth`) was not found, so its estimates cannot be "
                "compared with it."
            )
        doc.banner(
            "SIMULATED DATA",
            f"These are simulated participants, not people: {drawn} The verdicts test the "
            "analysis, not the robot's handwriting.",
        )


def build_report(analysis: Analysis, reproduced: pd.DataFrame | None = None) -> Doc:
    """The report as a :class:`Doc` (render with ``.markdown()`` / ``.html()``)."""
    name = analysis.config.name
    file = Path(analysis.source).name
    title = f"User-study analysis: {name} ({file})" if name else f"User-study analysis: {file}"
    doc = Doc(title + ORIGIN_TITLES.get(analysis.origin, ""))
    _origin_banner(doc, analysis)
    doc.h(2, "Summary")
    doc.ul([line for st in analysis.studies for line in st.conclusions])
    for st in analysis.studies:
        if st.truth is not None:
            from studies.analysis.truth import headline

            doc.table(
                headline(st),
                f"{st.kind}: the main estimates beside the simulation's truth (every table "
                "below has a truth column too).",
            )
    doc.h(2, "Data")
    att = analysis.attention
    failed = att.loc[att["failed_any"], "participant_id"].tolist()
    items = [
        f"File `{analysis.source}`: {analysis.rows_in_file} rows, {att['participant_id'].nunique()} participants.",
        f"Attention checks: {int(att['checks'].sum())} check trials; {len(failed)} participants failed at least one"
        + (
            f" ({', '.join(map(str, failed[:10]))}{' ...' if len(failed) > 10 else ''})."
            if failed
            else "."
        ),
    ]
    items += [
        f"Analysed ({st.kind}): {st.data['participant_id'].nunique()} participants, {len(st.data)} trials."
        for st in analysis.studies
    ]
    items += analysis.notes
    doc.ul(items)
    for st in analysis.studies:
        (_study1_section if st.kind == TURING else _study2_section)(doc, st)
    _paper_section(doc, reproduced, analysis)
    _methods(doc, analysis)
    return doc


def judge_section(doc: Doc, judge: dict) -> None:
    """What the automatic judge (``prg-study judge``, :mod:`studies.judge`) said of the study's
    stimuli before any participant saw them."""
    doc.h(2, "Before the participants: the automatic judge")
    obs = judge["observer"]
    doc.p(
        f"`prg-study judge` on `{judge['folder']}`: {judge['words']} words, "
        f"{judge['robot_samples']} robot and {judge['human_samples']} human samples. A linear "
        "classifier trained leaving one word out tells the robot's words from the people's "
        "(balanced accuracy, 0.5: indistinguishable); a simulated observer picks the robot among "
        f"{judge['n_options']} (chance {judge['chance']:.2f}, the paper's participants "
        f"{judge['paper_participants']:.2f})."
    )
    rows = [
        {
            "measure": f"C2ST, {name}",
            "value": f"{c['balanced_accuracy']:.2f}",
            "95 % CI": f"{c['ci95'][0]:.2f}-{c['ci95'][1]:.2f}",
        }
        for name, c in judge["c2st"].items()
    ]
    rows.append(
        {
            "measure": "simulated observer's pick rate",
            "value": f"{obs['pick_rate']:.2f}",
            "95 % CI": f"{obs['ci95'][0]:.2f}-{obs['ci95'][1]:.2f}",
        }
    )
    doc.table(pd.DataFrame(rows), "The judge's scores (95 % intervals by bootstrapping the words).")
