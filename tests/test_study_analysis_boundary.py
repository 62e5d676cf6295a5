"""Boundary studies through ``prg-study analyze``: every answer the same, participants and words at
0 % and 100 %, perfect separation of the writers. Each must exit 0 and write a report in which a
model that cannot be fitted says so (no estimate, NaN p, the reason) and every interval contains
its rate and stays inside [0, 1]."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from studies.analysis import stats as S
from studies.analysis.participants import simulate_readability, simulate_turing
from studies.cli import main

N = 24  # participants: enough for the GEE (>= 20 clusters) and quick


def _answered(frame: pd.DataFrame) -> pd.Series:
    return frame["is_attention_check"].astype(str) != "true"


def set_turing(frame: pd.DataFrame, where: pd.Series, picked_robot: bool) -> None:
    """Rows ``where`` (not attention checks) pick the robot's sample, or a human's."""
    m = where & _answered(frame)
    robot = frame.loc[m, "robot_index"].astype(int)
    frame.loc[m, "chosen_index"] = robot if picked_robot else (robot + 1) % 5
    frame.loc[m, "chose_robot"] = "true" if picked_robot else "false"


def set_readability(frame: pd.DataFrame, where: pd.Series, correct: bool) -> None:
    m = where & _answered(frame)
    frame.loc[m, "typed_text"] = frame.loc[m, "word"] if correct else "???"
    frame.loc[m, "correct"] = "true" if correct else "false"


def turing(case: str) -> pd.DataFrame:
    frame, _ = simulate_turing(N, 0.3, seed=5)
    everyone = pd.Series(True, index=frame.index)
    people = sorted(frame["participant_id"].unique())
    words = sorted(frame.loc[_answered(frame), "word"].unique())
    if case in ("all-robot", "all-human"):
        set_turing(frame, everyone, case == "all-robot")
        rating = 5 if case == "all-robot" else 3  # every rating the same too
        frame.loc[_answered(frame), "confidence"] = rating
    elif case == "participants-0-100":
        set_turing(frame, frame["participant_id"].isin(people[:4]), True)
        set_turing(frame, frame["participant_id"].isin(people[4:8]), False)
    elif case == "words-0-100":
        set_turing(frame, frame["word"] == words[0], True)
        set_turing(frame, frame["word"] == words[1], False)
    return frame


def readability(case: str) -> pd.DataFrame:
    frame, _ = simulate_readability(N, 0.7, seed=6)
    everyone = pd.Series(True, index=frame.index)
    people = sorted(frame["participant_id"].unique())
    words = sorted(frame.loc[_answered(frame), "word"].unique())
    robot = frame["writer"] == "robot"
    if case in ("all-correct", "all-wrong"):
        set_readability(frame, everyone, case == "all-correct")
    elif case == "separation":  # every robot word read, no human word
        set_readability(frame, robot, True)
        set_readability(frame, ~robot, False)
    elif case == "robot-all-correct":  # quasi-separation: the human's answers vary
        set_readability(frame, robot, True)
    elif case == "participants-0-100":
        set_readability(frame, frame["participant_id"].isin(people[:4]), True)
        set_readability(frame, frame["participant_id"].isin(people[4:8]), False)
    elif case == "words-0-100":
        set_readability(frame, frame["word"] == words[0], True)
        set_readability(frame, frame["word"] == words[1], False)
    return frame


def analyze(tmp_path: Path, frame: pd.DataFrame, capsys) -> Path:
    src = tmp_path / "responses.csv"
    frame.to_csv(src, index=False)
    out = tmp_path / "report"
    code = main(["analyze", str(src), "--out", str(out), "--no-paper"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "Traceback" not in captured.err
    assert (out / "report.html").is_file() and (out / "report.md").is_file()
    return out


def check_report(out: Path) -> tuple[pd.DataFrame, dict]:
    """The statistical invariants every report must hold, boundary or not."""
    tests = pd.read_csv(out / "tests.csv")
    for r in tests.itertuples(index=False):
        where = f"{r.test}: {r.conclusion}"
        if math.isfinite(r.p_value):
            assert 0 < r.p_value <= 1, where  # p = 0 is a division by a zero SE, not a test
            if not r.test.startswith("Wilcoxon"):  # the only test without an interval
                assert r.ci_low < r.ci_high and r.ci_low <= r.estimate <= r.ci_high, where
            assert not str(r.conclusion).startswith("not estimable"), where
        else:
            assert str(r.conclusion).startswith("not estimable: "), where
            assert len(str(r.conclusion)) > len("not estimable: ") + 10, where  # a reason
            assert not math.isfinite(r.ci_low) and not math.isfinite(r.ci_high), where
        if "rate" in str(r.null_hypothesis) and "-" not in r.test and math.isfinite(r.ci_low):
            assert r.ci_low >= 0 and r.ci_high <= 1, where
    for name in ("per_word.csv", "per_participant.csv"):
        table = pd.read_csv(out / name)
        assert ((table.ci_low <= table.rate) & (table.rate <= table.ci_high)).all(), name
        assert ((table.ci_low >= 0) & (table.ci_high <= 1)).all(), name
        assert (table.ci_low < table.ci_high).all(), name  # a rate of 0 or 1 is not certain
    mixed = pd.read_csv(out / "mixed_model.csv")
    status = str(mixed.status.iloc[0])
    if not status.startswith(("ok", "converged")):
        assert status.startswith(("failed: ", "skipped: ")) and len(mixed) == 1, status
    md = (out / "report.md").read_text("utf-8")
    assert " nan" not in md.lower() and "p = 0 " not in md and "p = 0)" not in md
    return tests, json.loads((out / "metrics.json").read_text("utf-8"))


def row(tests: pd.DataFrame, start: str) -> pd.Series:
    hit = tests[tests.test.str.startswith(start)]
    assert len(hit), start
    return hit.iloc[0]


@pytest.mark.filterwarnings("error::RuntimeWarning")  # e.g. scipy's "catastrophic cancellation"
@pytest.mark.parametrize("case", ["all-robot", "all-human"])
def test_turing_study_where_every_answer_is_the_same(tmp_path, capsys, case):
    out = analyze(tmp_path, turing(case), capsys)
    tests, metrics = check_report(out)
    y = 1.0 if case == "all-robot" else 0.0
    for name in ("GEE rate vs chance", "GEE TOST vs chance", "one-sample t-test vs 0.2"):
        assert np.isnan(row(tests, name).p_value), name  # infinite log-odds, no spread
    exact = row(tests, "exact binomial test vs chance")
    assert exact.estimate == y and exact.ci_low < exact.ci_high
    assert (exact.ci_high if y else exact.ci_low) == y  # the bound is the rate itself
    for name in ("one-sample t-test vs 3 on ratings", "one-sample t-test vs 3 on participant"):
        assert np.isnan(row(tests, name).p_value), name  # every rating the same
    verdict = metrics["studies"]["turing"]
    assert verdict["h1"] == "not estimable" and "log-odds are infinite" in verdict["h1_reason"]
    assert verdict["h2"] == "not estimable" and "zero variance" in verdict["h2_reason"]
    status = pd.read_csv(out / "mixed_model.csv").status.iloc[0]
    assert status.startswith(f"failed: every answer is {y:g}")
    summary = (out / "report.md").read_text("utf-8")
    assert "**H1**: not estimable from these data:" in summary
    assert "**H2**: not estimable" in summary


@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("case", ["participants-0-100", "words-0-100"])
def test_turing_participants_and_words_at_0_and_100_percent(tmp_path, capsys, case):
    out = analyze(tmp_path, turing(case), capsys)
    tests, metrics = check_report(out)
    gee = row(tests, "GEE rate vs chance")
    assert np.isfinite(gee.p_value)  # a few people or words at 0/100 % is no separation
    assert metrics["studies"]["turing"]["h1"] != "not estimable"
    by = "per_participant.csv" if case.startswith("participants") else "per_word.csv"
    table = pd.read_csv(out / by)
    assert {0.0, 1.0} <= set(table.rate)
    assert (table[table.rate == 0].ci_low == 0).all() and (
        table[table.rate == 1].ci_high == 1
    ).all()


@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("case", ["all-correct", "all-wrong", "separation"])
def test_readability_study_without_variation_is_reported_not_estimable(tmp_path, capsys, case):
    out = analyze(tmp_path, readability(case), capsys)
    tests, metrics = check_report(out)
    for name in (
        "independent t-test on word rates",
        "paired t-test by participant",
        "GEE difference",
        "paired t-test by word",
    ):
        assert np.isnan(row(tests, name).p_value), name
    verdict = metrics["studies"]["readability"]
    assert verdict["verdict"] == "not estimable" and "zero variance" in verdict["reason"]
    status = pd.read_csv(out / "mixed_model.csv").status.iloc[0]
    assert status.startswith("failed: ")
    if case == "separation":
        assert "perfect separation" in row(tests, "GEE difference").conclusion
        assert "separation" in status
    assert "**Readability**: not estimable from these data:" in (out / "report.md").read_text()


@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("case", ["robot-all-correct", "participants-0-100", "words-0-100"])
def test_readability_participants_words_and_one_writer_at_the_boundary(tmp_path, capsys, case):
    out = analyze(tmp_path, readability(case), capsys)
    tests, metrics = check_report(out)
    paired = row(tests, "paired t-test by participant")
    assert np.isfinite(paired.p_value)  # the paired differences still vary
    assert metrics["studies"]["readability"]["verdict"] != "not estimable"
    status = pd.read_csv(out / "mixed_model.csv").status.iloc[0]
    if case == "robot-all-correct":  # the writer effect's log-odds are infinite
        assert status.startswith("failed: separation: every robot answer is 1")
        assert "every robot answer is 1" in row(tests, "GEE difference").method
    else:
        table = pd.read_csv(
            out / ("per_word.csv" if case.startswith("words") else "per_participant.csv")
        )
        assert {0.0, 1.0} <= set(table.rate)


def test_zero_variance_tests_are_not_estimable_rather_than_p_zero():
    same = pd.DataFrame({"participant_id": range(8), "v": 5.0})
    t = S.one_sample_ttest(same, "v", 3, "two-sided", cluster="participant_id").iloc[0]
    assert t.estimate == 5 and np.isnan([t.p_value, t.ci_low, t.statistic]).all()
    assert "zero variance" in t.conclusion
    # round-off in the means (1/3 vs 2/6) is no variance either
    thirds = pd.DataFrame(
        {"participant_id": [0, 0, 0, 1, 1, 1, 1, 1, 1], "v": [1, 0, 0, 1, 1, 0, 0, 0, 0]}
    )
    assert np.isnan(S.one_sample_ttest(thirds, "v", 0.2, cluster="participant_id").p_value.iloc[0])
    # one value spread is enough: a real t-test
    spread = pd.DataFrame({"participant_id": range(8), "v": [5.0] * 7 + [4.0]})
    assert np.isfinite(S.one_sample_ttest(spread, "v", 3, cluster="participant_id").p_value.iloc[0])


def test_a_turing_margin_that_leaves_zero_to_one_is_refused_before_anything_is_written(
    tmp_path, capsys
):
    src = tmp_path / "responses.csv"
    turing("participants-0-100").to_csv(src, index=False)
    out = tmp_path / "report"
    assert main(["analyze", str(src), "--margin", "0.5", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("prg-study: error: chance 0.2 ± "), err
    assert "--margin" in err[0] and not out.exists()
