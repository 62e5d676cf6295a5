"""Tests of ``studies.analysis.validate`` (moved from the suite on: simulated participants with
known truth: the simulator honours the truth it is given, and the analysis reaches the right
conclusions from its responses)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from prg.errors import UsageError
from studies.analysis import stats as S
from studies.analysis.config import AnalysisSettings, with_overrides
from studies.analysis.validate import (
    ResponseFileError,
    analysis_rows,
    attention_summary,
    check_responses,
    load_responses,
)
from tests.helpers.study_analysis_simulated import turing_rows
from tests.helpers.study_analysis_validate import readability_table, turing_table  # noqa: F401 (fixtures)


def test_simulated_rate_and_icc_are_recovered_on_a_large_sample():
    rows, _ = turing_rows(participants=400, rate=0.3, icc=0.15, seed=11)
    assert rows["chose_robot"].mean() == pytest.approx(0.3, abs=0.02)
    assert S.icc_oneway(rows, "chose_robot").icc.iloc[0] == pytest.approx(0.15, abs=0.04)
    assert rows["confidence"].mean() == pytest.approx(3.0, abs=0.1)


def write(tmp_path: Path, table: pd.DataFrame, name: str = "responses.csv") -> Path:
    path = tmp_path / name
    table.to_csv(path, index=False)
    return path


# --------------------------------------------------------------------------- reading


def test_a_simulated_file_reads_back_typed(tmp_path, turing_table):
    resp = load_responses(write(tmp_path, turing_table))
    f = resp.frame
    assert resp.kinds == ["turing"] and len(f) == len(turing_table)
    assert (
        set(f["chose_robot"].dropna()) <= {0.0, 1.0}
        and f["confidence"].dropna().between(1, 5).all()
    )
    assert f["is_attention_check"].dtype == bool and f["line"].iloc[0] == 2


def test_out_of_range_confidence_is_one_line_naming_file_line_and_range(tmp_path, turing_table):
    t = turing_table.copy()
    t.loc[15, "confidence"] = "7"
    path = write(tmp_path, t)
    with pytest.raises(ResponseFileError) as err:
        load_responses(path)
    assert (
        str(err.value) == f"{path} line 17: confidence 7 is outside 1-5 (accepted: an integer 1-5)"
    )


def test_missing_column_is_named_with_what_the_study_needs(tmp_path, turing_table):
    path = write(tmp_path, turing_table.drop(columns=["confidence"]))
    with pytest.raises(
        ResponseFileError, match=r"line 1: missing column confidence \(the turing study needs"
    ):
        load_responses(path)


def test_duplicate_trial_names_both_lines(tmp_path, turing_table):
    t = pd.concat([turing_table, turing_table.iloc[[3]]], ignore_index=True)
    with pytest.raises(
        ResponseFileError,
        match=rf"line {len(t) + 1}: duplicate trial: participant 'P0001' trial 3 is also on line 5",
    ):
        load_responses(write(tmp_path, t))


def test_several_problems_show_the_first_three_on_one_line_and_keep_all(tmp_path, turing_table):
    t = turing_table.copy()
    t.loc[2, "chose_robot"] = "maybe"
    t.loc[4, "robot_index"] = "9"
    t.loc[6, "rt_ms"] = "fast"
    t.loc[8, "participant_id"] = ""
    with pytest.raises(ResponseFileError) as err:
        load_responses(write(tmp_path, t))
    msg = str(err.value)
    assert "\n" not in msg and msg.endswith("(and 2 more problems)")
    assert "line 4: chose_robot 'maybe' is not true/false (1/0)" in msg
    assert "line 6: robot_index 9 is outside 0-4" in msg
    assert len(err.value.problems) == 5  # a bad robot_index also contradicts chose_robot


def test_chose_robot_contradicting_the_indices_is_reported(turing_table):
    t = turing_table.copy()
    i = t.index[(t.is_attention_check == "false")][0]
    t.loc[i, "chose_robot"] = "false" if t.loc[i, "chose_robot"] == "true" else "true"
    with pytest.raises(ResponseFileError, match=r"chose_robot \w+ contradicts chosen_index"):
        check_responses(t, "responses.csv")


def test_unknown_study_and_writer_values_are_reported(readability_table):
    t = readability_table.copy()
    t.loc[0, "study"] = "study 3"
    with pytest.raises(
        ResponseFileError, match="line 2: study 'study 3' is not turing or readability"
    ):
        check_responses(t)
    t = readability_table.copy()
    t.loc[1, "writer"] = "alien"
    with pytest.raises(ResponseFileError, match="line 3: writer 'alien' is not human or robot"):
        check_responses(t)


def test_unreadable_files_are_one_line_usage_errors(tmp_path):
    with pytest.raises(UsageError, match="no such responses file"):
        load_responses(tmp_path / "nope.csv")
    (tmp_path / "empty.csv").write_text("")
    with pytest.raises(UsageError, match="empty file"):
        load_responses(tmp_path / "empty.csv")
    (tmp_path / "header.csv").write_text("participant_id,word,chose_robot,confidence\n")
    with pytest.raises(UsageError, match="no rows after the header"):
        load_responses(tmp_path / "header.csv")
    (tmp_path / "ragged.csv").write_text("a,b\n1,2\n1,2,3\n")
    with pytest.raises(UsageError, match="not a well-formed CSV"):
        load_responses(tmp_path / "ragged.csv")


def test_chose_robot_is_derived_from_the_indices_when_absent(turing_table):
    resp = check_responses(turing_table.drop(columns=["chose_robot"]))
    f = resp.frame
    assert (f["chose_robot"] == (f["chosen_index"] == f["robot_index"])).all()
    assert any("taken from chosen_index == robot_index" in n for n in resp.notes)


def test_correct_is_scored_from_typed_text_when_absent(readability_table):
    t = readability_table.drop(columns=["correct"])
    t.loc[0, "typed_text"] = "  " + t.loc[0, "word"].upper() + " "
    resp = check_responses(t)
    assert resp.frame.loc[0, "correct"] == 1.0
    truth = readability_table["correct"].eq("true").astype(float)
    assert (resp.frame["correct"].iloc[1:] == truth.iloc[1:].to_numpy()).all()


def test_a_file_without_a_study_column_is_guessed_from_its_columns_or_refused(readability_table):
    assert check_responses(readability_table.drop(columns=["study"])).kinds == ["readability"]
    bare = pd.DataFrame({"participant_id": ["a"], "word": ["cat"]})
    with pytest.raises(UsageError, match="cannot tell which study"):
        check_responses(bare)


def test_kind_keeps_only_that_studys_rows(turing_table, readability_table):
    both = pd.concat([turing_table, readability_table], ignore_index=True).fillna("")
    assert check_responses(both).kinds == ["turing", "readability"]
    only = check_responses(both, kind="readability")
    assert only.kinds == ["readability"] and any(
        "another study were left out" in n for n in only.notes
    )


# --------------------------------------------------------------------------- attention checks


def test_attention_rows_and_failing_participants_are_excluded_by_default(turing_table):
    frame = check_responses(turing_table).frame
    att = attention_summary(frame)
    assert att.loc[att.failed_any, "participant_id"].tolist() == ["P0007"]
    used, notes = analysis_rows(frame)
    assert not used["is_attention_check"].any() and "P0007" not in set(used.participant_id)
    assert any("failed an attention check and were excluded: P0007" in n for n in notes)


def test_attention_options_keep_rows_and_participants(turing_table):
    frame = check_responses(turing_table).frame
    used, notes = analysis_rows(frame, include_attention_rows=True, exclude_failed=False)
    assert used["is_attention_check"].sum() == 7 and "P0007" in set(used.participant_id)
    assert any("(kept)" in n for n in notes)


def test_a_chance_of_one_in_k_allows_k_samples_per_trial(turing_table):
    cfg = with_overrides(AnalysisSettings(), chance=1 / 6)
    assert cfg.n_options == 6
    t = turing_table.copy()
    i = t.index[t.is_attention_check == "false"][0]
    t.loc[i, ["robot_index", "chosen_index", "chose_robot"]] = ["5", "5", "true"]
    assert check_responses(t, n_options=cfg.n_options).frame.loc[i, "chose_robot"] == 1.0
    with pytest.raises(ResponseFileError, match="robot_index 5 is outside 0-4"):
        check_responses(t)
