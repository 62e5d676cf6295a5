"""Tests of ``studies.analysis.schema`` (moved from the suite on: `prg-study analyze | simulate`:
the report folder (Markdown, self-contained HTML, tidy CSVs, figures), written atomically; bad
input is one line with exit code 2)."""

from __future__ import annotations

import json

import pandas as pd

from studies.analysis.schema import COLUMNS, STUDY1_COLUMNS, STUDY2_COLUMNS
from tests.helpers.study_analysis_report import both_studies  # noqa: F401 (fixtures)
from tests.helpers.study_analysis_validate import readability_table, turing_table  # noqa: F401 (fixtures)


def test_simulate_writes_the_schema_and_its_truth(both_studies):
    folder = both_studies[0].parent
    assert tuple(pd.read_csv(folder / "t.csv").columns) == STUDY1_COLUMNS
    truth = json.loads((folder / "t.truth.json").read_text())
    assert (truth["kind"], truth["rate"], truth["icc"], truth["inattentive"]) == (
        "turing",
        0.45,
        0.1,
        3,
    )


# --------------------------------------------------------------------------- schema


def test_schema_columns_are_exact_and_ordered():
    assert STUDY1_COLUMNS == (
        "participant_id",
        "session_id",
        "study",
        "list_id",
        "trial",
        "word",
        "robot_index",
        "chosen_index",
        "chose_robot",
        "confidence",
        "rt_ms",
        "is_attention_check",
        "attention_pass",
        "timestamp",
        "app_version",
        "seed",
    )
    assert STUDY2_COLUMNS == (
        "participant_id",
        "session_id",
        "study",
        "list_id",
        "trial",
        "word",
        "writer",
        "typed_text",
        "correct",
        "rt_ms",
        "is_attention_check",
        "attention_pass",
        "timestamp",
        "app_version",
        "seed",
    )
    assert set(STUDY1_COLUMNS) | set(STUDY2_COLUMNS) == set(COLUMNS)


def test_simulator_writes_exactly_the_schema_columns(turing_table, readability_table):
    assert tuple(turing_table.columns) == STUDY1_COLUMNS
    assert tuple(readability_table.columns) == STUDY2_COLUMNS
