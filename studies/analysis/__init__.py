"""Analysis of the human-vs-robot handwriting user studies (``prg-study analyze | power | simulate``).

Modules:

- :mod:`~studies.analysis.schema` — the response file's exact columns (no heavy imports);
- :mod:`~studies.analysis.validate` — read and check a responses CSV, attention checks;
- :mod:`~studies.analysis.config` — analysis options from the study YAML and the command line;
- :mod:`~studies.analysis.stats` — paper-faithful and recommended tests (tidy frames in and out),
  one module per family of tests;
- :mod:`~studies.analysis.analyze` — every test of a study, conclusions and verdicts;
- :mod:`~studies.analysis.report` — Markdown/HTML report, figures, CSVs (atomic);
- :mod:`~studies.analysis.crossed_logit` — the crossed logit model of the answers, calibrated;
- :mod:`~studies.analysis.power` — power and sample size for both studies;
- :mod:`~studies.analysis.participants` — simulated participants with known truth;
- :mod:`~studies.analysis.paper` — the paper's numbers reproduced from its summaries;
- :mod:`~studies.analysis.commands` — the ``analyze``, ``power`` and ``simulate`` sub-commands.

Names are imported lazily so that ``studies.analysis.schema`` stays cheap to import.
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "load_responses": "validate",
    "analysis_rows": "validate",
    "ResponseFileError": "validate",
    "AnalysisSettings": "config",
    "load_config": "config",
    "analyze_file": "analyze",
    "analyze_turing": "analyze",
    "analyze_readability": "analyze",
    "write_report": "report",
    "simulate_turing": "participants",
    "simulate_readability": "participants",
    "reproduce_paper": "paper",
    "register": "commands",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(f"studies.analysis.{_EXPORTS[name]}"), name)
    raise AttributeError(f"module 'studies.analysis' has no attribute {name!r}")
