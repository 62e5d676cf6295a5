"""Helpers shared by the tests that were split out of tests/test_study_analysis_report.py."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd
import pytest

from prg.errors import PRGError
from studies.analysis.commands import register


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
