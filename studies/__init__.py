"""User-study toolkit (human vs robot handwriting): design, stimuli, web bundles, analysis.

- :mod:`studies.design_config` — the study YAML (``conf/study/``), read and checked;
- :mod:`studies.design` — a study's counterbalanced trial lists;
- :mod:`studies.stimuli` — robot and human samples, drawn alike to PNG;
- :mod:`studies.bundle` — the static web folder (questionnaire and capture page);
- :mod:`studies.analysis` — reading the responses, the statistics, power, reports;
- :mod:`studies.program` — the ``prg-study`` program: parser, ``build``, errors and exit codes;
- :mod:`studies.cli` — the ``prg-study`` command (``build``, ``analyze``, ``power``, ``simulate``).
"""
