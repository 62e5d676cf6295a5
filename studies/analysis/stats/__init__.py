"""Statistics for the two user studies: tidy frames in, tidy frames out.

Every function takes a long-format DataFrame (one row per trial) plus column names and returns
a tidy DataFrame. Test results share the columns of :data:`TEST_COLUMNS` (one row per test);
rate tables those of :func:`rates_by`.

Two families:

*Paper-faithful* — what the paper did, treating every trial as independent:
:func:`binomial_test` (exact, vs chance), :func:`binomial_tost` (exact binomial TOST),
:func:`one_sample_ttest` without ``cluster`` (H2 on all ratings), :func:`group_ttest`
(study 2: independent t-test on the words' success rates).

*Recommended* — what a careful reviewer asks for: :func:`rates_by` (per-participant and
per-word rates with Wilson CIs), :func:`gee_rate` (GEE on participants, test vs chance and TOST),
:func:`one_sample_ttest` with ``cluster`` (H2 on participant means), :func:`signed_rank_test`,
:func:`paired_tests` (paired t, paired TOST, non-inferiority), :func:`gee_difference`,
:func:`mixed_logit` (crossed participants x words, variational Bayes), :func:`icc_oneway`,
:func:`margin_warnings`.

One module per family of tests, all names importable from here:

- :mod:`~studies.analysis.stats.common` — the result frame and its decision, reading columns, the
  logit, p values;
- :mod:`~studies.analysis.stats.proportions` — rate CIs, the exact binomial test, rates per level;
- :mod:`~studies.analysis.stats.parametric` — one-sample, independent and paired t-tests;
- :mod:`~studies.analysis.stats.nonparametric` — the Wilcoxon signed-rank test;
- :mod:`~studies.analysis.stats.equivalence` — TOST and non-inferiority, the margin's warnings;
- :mod:`~studies.analysis.stats.gee` — GEE rate vs chance and GEE difference;
- :mod:`~studies.analysis.stats.mixed` — the crossed mixed logit;
- :mod:`~studies.analysis.stats.reliability` — ICC(1) and the design effect.

The tests in ``tests/studies/analysis/`` check each function against the scipy or
statsmodels call its docstring names.
"""

from __future__ import annotations

from studies.analysis.stats.common import TEST_COLUMNS, expit, format_p, logit, tests_frame
from studies.analysis.stats.equivalence import binomial_tost, margin_candidates, margin_warnings
from studies.analysis.stats.gee import gee_difference, gee_rate
from studies.analysis.stats.mixed import MIXED_COLUMNS, mixed_logit
from studies.analysis.stats.nonparametric import signed_rank_test
from studies.analysis.stats.parametric import group_ttest, one_sample_ttest, paired_tests
from studies.analysis.stats.proportions import (
    binomial_test,
    proportion_ci,
    proportion_intervals,
    rates_by,
)
from studies.analysis.stats.reliability import icc_oneway

__all__ = [
    "MIXED_COLUMNS",
    "TEST_COLUMNS",
    "binomial_test",
    "binomial_tost",
    "expit",
    "format_p",
    "gee_difference",
    "gee_rate",
    "group_ttest",
    "icc_oneway",
    "logit",
    "margin_candidates",
    "margin_warnings",
    "mixed_logit",
    "one_sample_ttest",
    "paired_tests",
    "proportion_ci",
    "proportion_intervals",
    "rates_by",
    "signed_rank_test",
    "tests_frame",
]
