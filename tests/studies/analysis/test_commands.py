"""Tests of ``studies.analysis.commands`` (moved from the suite on: `prg-study analyze | simulate`:
the report folder (Markdown, self-contained HTML, tidy CSVs, figures), written atomically; bad
input is one line with exit code 2)."""

from __future__ import annotations

import argparse
import json
import re

import pandas as pd
import pytest

from studies.analysis.commands import register
from tests.helpers.study_analysis_report import both_studies, cli  # noqa: F401 (fixtures)

FIGURES = {
    "turing_per_word.png",
    "turing_participants.png",
    "turing_confidence.png",
    "readability_per_writer.png",
    "readability_differences.png",
}


def test_analyze_writes_the_whole_report_folder(both_studies):
    out = both_studies[1]
    names = {p.name for p in out.iterdir()}
    assert names == {
        "report.md",
        "report.html",
        "tests.csv",
        "per_word.csv",
        "per_participant.csv",
        "mixed_model.csv",
        "paper_reproduction.csv",
        "metrics.json",
        "figures",
    }
    assert {p.name for p in (out / "figures").iterdir()} == FIGURES
    assert all((out / "figures" / f).read_bytes()[:4] == b"\x89PNG" for f in FIGURES)
    assert not [p for p in out.parent.iterdir() if ".tmp-" in p.name or ".old-" in p.name]


def test_report_html_is_self_contained_with_embedded_figures(both_studies):
    page = (both_studies[1] / "report.html").read_text()
    assert page.count("data:image/png;base64,") == len(FIGURES)
    assert 'src="figures/' not in page and "<script" not in page
    assert "<h2>Where the paper&#x27;s analysis was weak</h2>" in page


def test_report_reads_as_summary_then_studies_then_the_papers_weaknesses(both_studies):
    md = (both_studies[1] / "report.md").read_text()
    heads = [line for line in md.splitlines() if line.startswith("## ")]
    assert heads == [
        "## Summary",
        "## Data",
        "## Study 1: Turing-like test",
        "## Study 2: readability",
        "## Where the paper's analysis was weak",
        "## Methods",
    ]
    assert "**H1 not supported**" in md and "3 participants failed at least one" in md
    for weakness in (
        "wrong null",
        "derived from the data",
        "treated as independent",
        "unpaired test",
        "'Not rejected' is not 'equal'",
    ):
        assert weakness in md
    assert "![" in md and "](figures/turing_per_word.png)" in md


def test_per_word_and_per_participant_csvs(both_studies):
    words = pd.read_csv(both_studies[1] / "per_word.csv")
    assert (
        len(words[words.study == "turing"]) == 10 and len(words[words.study == "readability"]) == 20
    )
    parts = pd.read_csv(both_studies[1] / "per_participant.csv")
    turing = parts[parts.study == "turing"]
    assert turing.excluded.sum() == 3 and (~turing.excluded).sum() == 40
    assert {"rate", "ci_low", "ci_high", "mean_confidence", "attention_failed"} <= set(
        parts.columns
    )
    assert {"rate_human", "rate_robot", "difference"} <= set(parts.columns)


def test_metrics_json_holds_the_verdicts(both_studies):
    metrics = json.loads((both_studies[1] / "metrics.json").read_text())
    assert metrics["studies"]["turing"]["h1"] == "above chance"
    assert metrics["studies"]["readability"]["verdict"] in {
        "equally readable",
        "non-inferior",
        "inconclusive",
    }


def test_a_margin_taken_from_the_data_is_warned_about(tmp_path, both_studies):
    cfg = tmp_path / "turing.yaml"
    cfg.write_text(
        "name: turing\nkind: turing\nequivalence_margin: 0.057\nanalysis:\n  margin_source: data\n"
    )
    assert (
        cli(
            "analyze",
            str(both_studies[0]),
            "--study",
            str(cfg),
            "--no-mixed",
            "--no-paper",
            "--out",
            str(tmp_path / "rep"),
        )
        == 0
    )
    md = (tmp_path / "rep" / "report.md").read_text()
    assert "> **Warning:** the equivalence margin 0.057 was derived from the data" in md
    assert "## Study 2" not in md  # kind: turing keeps study 1's rows only
    assert json.loads((tmp_path / "rep" / "metrics.json").read_text())["warnings"]


def test_a_failed_run_leaves_the_previous_report_untouched(tmp_path, both_studies, capsys):
    out = tmp_path / "rep"
    out.mkdir()
    (out / "report.md").write_text("previous")
    bad = pd.read_csv(both_studies[0], dtype=str, keep_default_na=False)
    bad.loc[3, "confidence"] = "9"
    bad.to_csv(tmp_path / "bad.csv", index=False)
    assert cli("analyze", str(tmp_path / "bad.csv"), "--out", str(out)) == 2
    err = capsys.readouterr().err.strip()
    assert (
        err
        == f"prg-study: error: {tmp_path / 'bad.csv'} line 5: confidence 9 is outside 1-5 (accepted: an integer 1-5)"
    )
    assert [p.name for p in out.iterdir()] == ["report.md"] and (
        out / "report.md"
    ).read_text() == "previous"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv", "rep"]


def test_analyze_refuses_to_write_into_a_folder_that_is_not_a_report(
    tmp_path, both_studies, capsys
):
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "thesis.tex").write_text("x")
    assert cli("analyze", str(both_studies[0]), "--no-mixed", "--out", str(tmp_path / "mine")) == 2
    assert "exists and is not an earlier report folder" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["simulate", "turing", "--participants", "0", "--true-rate", "0.2", "--out", "x.csv"],
            "argument --participants: 0 must be at least 1",
        ),
        (
            ["simulate", "turing", "--participants", "5", "--true-rate", "1.2", "--out", "x.csv"],
            r"argument --true-rate: 1.2 is outside \(0, 1\)",
        ),
        (["power", "turing", "--icc", "0.7"], "argument --icc: 0.7 is outside 0-0.5"),
        (["analyze", "r.csv", "--alpha", "zero"], "argument --alpha: 'zero' is not a number"),
    ],
)
def test_bad_arguments_are_one_line_exit_2(capsys, argv, message):
    with pytest.raises(SystemExit) as exit_:
        cli(*argv)
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.count("\n") == 1
    assert re.search(message, err)


def test_simulate_refuses_a_human_rate_for_the_turing_study(tmp_path, capsys):
    assert (
        cli(
            "simulate",
            "turing",
            "--participants",
            "5",
            "--true-rate",
            "0.2",
            "--human-rate",
            "0.5",
            "--out",
            str(tmp_path / "x.csv"),
        )
        == 2
    )
    assert "--human-rate is for the readability study" in capsys.readouterr().err
    assert not (tmp_path / "x.csv").exists()


def run_power(capsys, *argv: str) -> str:
    parser = argparse.ArgumentParser(prog="prg-study")
    register(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(["power", *argv])
    assert args.func(args) == 0
    return capsys.readouterr().out


def test_power_command_prints_the_turing_plan_and_writes_csv(capsys, tmp_path):
    out = run_power(
        capsys,
        "turing",
        "--rate",
        "0.2",
        "--power",
        "0.8",
        "--words",
        "10",
        "--out",
        str(tmp_path / "p.csv"),
    )
    assert "570" in out and "0.731" in out
    plan = pd.read_csv(tmp_path / "p.csv")
    assert plan.loc[0, "trials"] == 570 and plan.loc[0, "words"] == 10


def test_power_command_for_readability_reports_tost_and_noninferiority(capsys):
    out = run_power(
        capsys,
        "readability",
        "--rate",
        "0.8",
        "--difference",
        "0",
        "--power",
        "0.8",
        "--participants",
        "30",
    )
    assert "paired TOST" in out and "non-inferiority" in out and "power_tost" in out
