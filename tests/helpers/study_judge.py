"""Helpers shared by the tests that were split out of tests/test_study_judge.py."""

from __future__ import annotations

from pathlib import Path

from studies.cli import main

REPO = Path(__file__).resolve().parents[2]


WORDS = ["cat", "dog", "sun", "egg", "ink", "owl"]


def _build(out: Path, robot: Path, human: Path, writers: int = 4) -> Path:
    args = ["build", str(REPO / "conf/study/turing.yaml"), "--out", str(out), "-q"]
    args += ["--robot", str(robot), "--human", str(human)]
    for s in (f"words=[{', '.join(WORDS)}]", f"human_writers={writers}", "foils=3"):
        args += ["--set", s]
    assert main(args) == 0
    return out
