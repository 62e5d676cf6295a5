"""`prg-study analyze | simulate`: the report folder (Markdown, self-contained HTML, tidy CSVs,
figures), written atomically; bad input is one line with exit code 2."""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from prg.errors import PRGError
from studies.analysis import stats as S
from studies.analysis.analyze import analyze_table
from studies.analysis.commands import register
from studies.analysis.config import AnalysisSettings
from studies.analysis.participants import simulate_turing
from studies.analysis.report import build_report
from studies.analysis.schema import STUDY1_COLUMNS
from studies.analysis.stats import TEST_COLUMNS

REPO = Path(__file__).resolve().parents[1]
FIGURES = {
    "turing_per_word.png",
    "turing_participants.png",
    "turing_confidence.png",
    "readability_per_writer.png",
    "readability_differences.png",
}


class OneLineParser(argparse.ArgumentParser):
    """Like the entry point's parser: errors are one line and exit 2."""

    def error(self, message):
        self.exit(2, f"prg-study: error: {' '.join(message.split())}\n")


def cli(*argv: str) -> int:
    """The sub-commands through a local harness, the way ``studies/cli.py`` runs them."""
    parser = OneLineParser(prog="prg-study")
    register(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(list(argv))
    try:
        return args.func(args)
    except PRGError as err:
        print(f"prg-study: error: {err}", file=sys.stderr)
        return err.exit_code


@pytest.fixture(scope="module")
def both_studies(tmp_path_factory) -> tuple[Path, Path]:
    """Both studies simulated (3 inattentive participants in study 1) and analysed into one report."""
    d = tmp_path_factory.mktemp("study")
    assert (
        cli(
            "simulate",
            "turing",
            "--participants",
            "40",
            "--true-rate",
            "0.45",
            "--icc",
            "0.1",
            "--inattentive",
            "3",
            "--seed",
            "1",
            "--out",
            str(d / "t.csv"),
        )
        == 0
    )
    assert (
        cli(
            "simulate",
            "readability",
            "--participants",
            "30",
            "--true-rate",
            "0.8",
            "--icc",
            "0.1",
            "--seed",
            "2",
            "--out",
            str(d / "r.csv"),
        )
        == 0
    )
    both = pd.concat([pd.read_csv(d / "t.csv", dtype=str), pd.read_csv(d / "r.csv", dtype=str)])
    both.to_csv(d / "responses.csv", index=False)
    assert (
        cli(
            "analyze",
            str(d / "responses.csv"),
            "--margin",
            "0.05",
            "--margin-source",
            "preregistered",
            "--out",
            str(d / "report"),
        )
        == 0
    )
    return d / "responses.csv", d / "report"


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


def test_tests_csv_is_tidy_one_row_per_test_for_both_approaches(both_studies):
    tests = pd.read_csv(both_studies[1] / "tests.csv")
    assert list(tests.columns) == ["study", "approach", "hypothesis", *TEST_COLUMNS]
    assert set(tests.approach) == {"paper-faithful", "recommended"}
    assert set(tests.study) == {"turing", "readability"}
    gee = tests[tests.test == "GEE rate vs chance"].iloc[0]
    assert gee.ci_low < gee.estimate < gee.ci_high and gee.p_value < 0.05 and gee.clusters == 40


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


def test_a_failed_mixed_model_is_reported_not_raised(monkeypatch):
    failed = pd.DataFrame(
        [
            dict.fromkeys(S.MIXED_COLUMNS, float("nan"))
            | {"term": "(model)", "type": "", "status": "failed: ValueError: no"}
        ]
    )
    monkeypatch.setattr(S, "mixed_logit", lambda *a, **k: failed)
    table, _ = simulate_turing(20, 0.3, seed=3)
    md = build_report(analyze_table(table, AnalysisSettings())).markdown()
    assert (
        "> **Warning:** The crossed mixed logit (participants x words) could not be fitted: ValueError: no."
        in md
    )


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


def test_module_runner_gives_one_line_errors_and_exit_codes(tmp_path):
    run = subprocess.run(
        [sys.executable, "-m", "studies.analysis.commands", "analyze", str(tmp_path / "none.csv")],
        cwd=REPO,
        capture_output=True,
        text=True,
    )
    assert run.returncode == 2
    assert (
        run.stderr
        == f"prg-study: error: {tmp_path / 'none.csv'}: no such responses file (expected a long-format CSV)\n"
    )
