"""Reports on data that are not people's answers to the study say so first: simulated
participants (with the simulation's truth beside every estimate) and a pilot build's answers;
the analysis never takes rows of different origins together."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pandas as pd
import pytest

from studies.analysis.schema import PILOT_SUFFIX, SIMULATED_VERSION
from tests.helpers.study_analysis_report import cli

RATE, ICC, HUMAN, ROBOT = 0.35, 0.1, 0.7, 0.85


@pytest.fixture(scope="module")
def simulated(tmp_path_factory) -> Path:
    """Both studies simulated and analysed, each into its own report (the demo's way)."""
    d = tmp_path_factory.mktemp("simulated")
    common = ["--seed", "3", "--word-icc", "0.05"]
    assert not cli(
        "simulate",
        "turing",
        "--participants",
        "60",
        "--true-rate",
        str(RATE),
        "--icc",
        str(ICC),
        *common,
        "--out",
        str(d / "turing.csv"),
    )
    assert not cli(
        "simulate",
        "readability",
        "--participants",
        "40",
        "--true-rate",
        str(ROBOT),
        "--human-rate",
        str(HUMAN),
        *common,
        "--out",
        str(d / "readability.csv"),
    )
    for kind in ("turing", "readability"):
        assert not cli("analyze", str(d / f"{kind}.csv"), "--out", str(d / kind), "--no-paper")
    return d


def first_screen(report: Path) -> list[str]:
    """The report's title and the block right under it."""
    lines = [line for line in (report / "report.md").read_text().splitlines() if line]
    return lines[:2]


@pytest.mark.parametrize("kind", ["turing", "readability"])
def test_a_simulated_report_says_so_in_its_title_and_first_block(simulated, kind):
    title, banner = first_screen(simulated / kind)
    assert title.endswith("— SIMULATED participants")
    assert banner.startswith("> **SIMULATED DATA** — These are simulated participants, not people")
    assert f"`{simulated / f'{kind}.truth.json'}`" in banner
    page = (simulated / kind / "report.html").read_text()
    assert page.index('class="banner"') < page.index("<h2>Summary</h2>")
    metrics = json.loads((simulated / kind / "metrics.json").read_text())
    assert metrics["origin"] == "simulated"
    assert metrics["truth"][kind] == json.loads((simulated / f"{kind}.truth.json").read_text())


def test_turing_estimates_stand_beside_the_simulated_rate(simulated):
    tests = pd.read_csv(simulated / "turing" / "tests.csv").set_index("test")
    h1 = tests[tests["hypothesis"].str.startswith("H1")]
    population = h1.drop(index=[t for t in h1.index if t.startswith("crossed mixed")])
    assert population["truth"].tolist() == [RATE] * len(population)
    typical = h1.loc["crossed mixed logit vs chance (typical participant and word)", "truth"]
    assert typical < RATE  # a typical participant's rate sits below the average one under 0.5
    assert tests.loc["one-sample t-test vs 3 on participant means", "truth"] == 3.0
    per_word = pd.read_csv(simulated / "turing" / "per_word.csv")
    assert per_word["truth"].nunique() == len(per_word)  # each word its own drawn effect
    assert per_word["truth"].mean() == pytest.approx(RATE, abs=0.05)
    mixed = pd.read_csv(simulated / "turing" / "mixed_model.csv").set_index("term")
    truth = json.loads((simulated / "turing.truth.json").read_text())["latent"]
    assert mixed.loc["sd(participant_id)", "truth"] == pytest.approx(truth["su"])
    md = (simulated / "turing" / "report.md").read_text()
    head = re.search(r"\| rate of picking the robot's sample \| ([\d.]+) \| ([\d.]+) \[", md)
    assert float(head.group(1)) == RATE
    assert float(head.group(2)) == pytest.approx(
        tests.loc["GEE rate vs chance", "estimate"], abs=1e-3
    )
    assert md.count("| truth |") >= 4  # H1, per word, mixed model, H2 tables


def test_readability_estimates_stand_beside_the_simulated_rates(simulated):
    tests = pd.read_csv(simulated / "readability" / "tests.csv")
    differences = tests[~tests["test"].str.startswith("crossed mixed")]
    assert differences["truth"].round(12).unique().tolist() == [round(ROBOT - HUMAN, 12)]
    md = (simulated / "readability" / "report.md").read_text()
    for quantity, rate in (("human success rate", HUMAN), ("robot success rate", ROBOT)):
        assert re.search(
            rf"\| {quantity} \| {rate:.3f} \| [\d.]+ \[[\d.]+, [\d.]+\] \| (yes|\*\*no\*\*) \|", md
        )
    per_word = pd.read_csv(simulated / "readability" / "per_word.csv")
    means = per_word.groupby("writer")["truth"].mean()
    assert means["human"] == pytest.approx(HUMAN, abs=0.05)
    assert means["robot"] == pytest.approx(ROBOT, abs=0.05)


def test_two_studies_in_one_file_take_one_truth_each(simulated, tmp_path, capsys):
    both = pd.concat(
        [pd.read_csv(simulated / f"{k}.csv", dtype=str) for k in ("turing", "readability")]
    )
    both.to_csv(tmp_path / "both.csv", index=False)
    truths = [str(simulated / f"{k}.truth.json") for k in ("turing", "readability")]
    args = ["analyze", str(tmp_path / "both.csv"), "--no-mixed", "--no-paper"]
    assert not cli(*args, "--truth", truths[0], "--out", str(tmp_path / "one"))
    banner = first_screen(tmp_path / "one")[1]
    assert "turing: 60 participants" in banner and "The truth of readability" in banner
    assert not cli(
        *args, "--truth", truths[0], "--truth", truths[1], "--out", str(tmp_path / "two")
    )
    assert "was not found" not in first_screen(tmp_path / "two")[1]
    assert "turing truth:" in capsys.readouterr().out
    assert cli(*args, "--truth", truths[0], "--truth", truths[0], "--out", str(tmp_path / "x")) == 2
    assert "a second truth for the turing study" in capsys.readouterr().err


def test_without_its_truth_file_a_simulated_report_still_says_simulated(simulated, tmp_path):
    (tmp_path / "alone.csv").write_bytes((simulated / "turing.csv").read_bytes())
    assert not cli(
        "analyze", str(tmp_path / "alone.csv"), "--out", str(tmp_path / "r"), "--no-mixed"
    )
    title, banner = first_screen(tmp_path / "r")
    assert title.endswith("SIMULATED participants") and "was not found" in banner
    assert "truth" not in pd.read_csv(tmp_path / "r" / "tests.csv").columns


def with_versions(simulated: Path, tmp_path: Path, version_of) -> Path:
    """The simulated turing responses with each participant's app_version set by ``version_of``."""
    table = pd.read_csv(simulated / "turing.csv", dtype=str, keep_default_na=False)
    assert set(table["app_version"]) == {SIMULATED_VERSION}
    table["app_version"] = table["participant_id"].map(version_of)
    path = tmp_path / "responses.csv"
    table.to_csv(path, index=False)
    return path


def test_a_pilot_builds_answers_are_reported_as_pilot_data(simulated, tmp_path, capsys):
    path = with_versions(simulated, tmp_path, lambda pid: "0.3.0+abc" + PILOT_SUFFIX)
    assert not cli("analyze", str(path), "--out", str(tmp_path / "r"), "--no-mixed", "--no-paper")
    title, banner = first_screen(tmp_path / "r")
    assert title.endswith("— PILOT data") and banner.startswith("> **PILOT DATA** —")
    assert "data: PILOT" in capsys.readouterr().out
    assert (
        cli(
            "analyze",
            str(path),
            "--truth",
            str(simulated / "turing.truth.json"),
            "--out",
            str(tmp_path / "t"),
        )
        == 2
    )
    assert "holds no simulated rows" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("second", "names"),
    [
        ("0.3.0+abc", "rows from the study's page"),
        ("0.3.0+abc" + PILOT_SUFFIX, "rows from a pilot build"),
    ],
)
def test_rows_of_two_origins_are_never_analysed_together(
    simulated, tmp_path, capsys, second, names
):
    path = with_versions(
        simulated, tmp_path, lambda pid: second if pid >= "P0031" else SIMULATED_VERSION
    )
    assert cli("analyze", str(path), "--out", str(tmp_path / "r")) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "never analysed together" in err
    assert "330 rows from the simulator (first on line 2)" in err and f"330 {names}" in err
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (None, "no such file"),
        ("{oops", "not valid JSON"),
        ('{"kind": "turing"}', "not a simulation's truth"),
    ],
)
def test_a_bad_truth_file_is_one_line_exit_2(simulated, tmp_path, capsys, content, message):
    truth = tmp_path / "t.truth.json"
    if content is not None:
        truth.write_text(content)
    code = cli(
        "analyze",
        str(simulated / "turing.csv"),
        "--truth",
        str(truth),
        "--out",
        str(tmp_path / "r"),
    )
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and f"--truth {truth}: {message}" in err


def test_the_truth_of_another_study_is_refused(simulated, tmp_path, capsys):
    code = cli(
        "analyze",
        str(simulated / "turing.csv"),
        "--truth",
        str(simulated / "readability.truth.json"),
        "--out",
        str(tmp_path / "r"),
    )
    assert code == 2
    assert "the truth of a readability simulation, but the responses analysed are turing" in (
        capsys.readouterr().err
    )
