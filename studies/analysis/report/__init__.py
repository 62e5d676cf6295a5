"""The analysis report: Markdown and self-contained HTML, figures, tidy CSVs — written atomically.

:func:`write_report` turns an :class:`~studies.analysis.analyze.Analysis` into a folder::

    report.md            the report (figures linked from figures/)
    report.html          the same report, figures embedded as base64 PNG (one file to send)
    tests.csv            one row per test: study, approach, hypothesis, estimate, CI, statistic, p, conclusion
    per_word.csv         per-word rates with Wilson CIs (study 1: p vs chance, Holm-adjusted)
    per_participant.csv  per-participant rates with CIs (+ confidence / per-writer rates), attention checks
    mixed_model.csv      crossed mixed-logit terms (or why the fit failed)
    paper_reproduction.csv  the paper's numbers reproduced from its summaries
    metrics.json         the verdicts, machine-readable
    figures/*.png

Everything is written into a temporary folder next to ``out`` and renamed into place, so a
failed run leaves the previous report untouched.

The package, one concept a module: :mod:`~studies.analysis.report.document` (the document
model, Markdown and HTML), :mod:`~studies.analysis.report.formatting` (numbers for people),
:mod:`~studies.analysis.report.figures`, :mod:`~studies.analysis.report.sections` (each study's
section), :mod:`~studies.analysis.report.build` (the whole report) and
:mod:`~studies.analysis.report.write` (the folder).
"""

from __future__ import annotations

from studies.analysis.report.build import ORIGIN_TITLES, build_report, judge_section
from studies.analysis.report.document import Doc
from studies.analysis.report.figures import (
    TRUTH_COLOR,
    fig_confidence,
    fig_differences,
    fig_readability,
    fig_turing_participants,
    fig_turing_words,
)
from studies.analysis.report.formatting import fmt_p, tests_table
from studies.analysis.report.write import REPORT_FILES, check_out_dir, write_report

__all__ = [
    "ORIGIN_TITLES",
    "REPORT_FILES",
    "TRUTH_COLOR",
    "Doc",
    "build_report",
    "check_out_dir",
    "fig_confidence",
    "fig_differences",
    "fig_readability",
    "fig_turing_participants",
    "fig_turing_words",
    "fmt_p",
    "judge_section",
    "tests_table",
    "write_report",
]
