"""User-study toolkit (human vs robot handwriting): design, stimuli, web bundles, analysis.

- :mod:`studies.design` — the study YAML (``conf/study/``) and its counterbalanced trial lists;
- :mod:`studies.stimuli` — robot and human samples, drawn alike to PNG;
- :mod:`studies.bundle` — the static web folder (questionnaire and capture page);
- :mod:`studies.analysis` — reading the responses, the statistics, power, reports;
- :mod:`studies.cli` — the ``prg-study`` command (``build``, ``analyze``, ``power``, ``simulate``).
"""
