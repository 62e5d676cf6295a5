"""What git holds: sources, configs, figures and result summaries, never a generated store,
checkpoint, recording or large log (``.ci/run`` also fails when ``make test`` leaves a file git
sees)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
#: generated files: stores (MLflow, Optuna), checkpoints, Rerun recordings, ROS bags
GENERATED = (".db", ".sqlite", ".ckpt", ".pt", ".rrd", ".mcap")
FIGURES = (".png", ".svg", ".jpg", ".gif")
MAX_BYTES = 300 * 1024


def _tracked() -> list[Path]:
    try:
        out = subprocess.run(
            ["git", "ls-files", "-z"], cwd=REPO, capture_output=True, check=True, timeout=60
        ).stdout
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout")
    return [REPO / name for name in out.decode().split("\0") if name]


def test_git_holds_no_store_checkpoint_or_recording():
    generated = [p.relative_to(REPO) for p in _tracked() if p.suffix in GENERATED]
    assert not generated, f"generated files in git: {generated}"


def test_git_holds_no_large_file_but_figures():
    large = [
        f"{p.relative_to(REPO)} ({p.stat().st_size // 1024} KB)"
        for p in _tracked()
        if p.is_file() and p.suffix not in FIGURES and p.stat().st_size > MAX_BYTES
    ]
    assert not large, f"files over {MAX_BYTES // 1024} KB in git: {large}"


def test_the_ignore_rules_cover_what_the_tools_write():
    probes = ["mlflow.db", "x/optuna.db", "models/m.ckpt", "run.rrd", "docs/_build/index.html"]
    probes += ["benchmarks/results/logs/bench_speech.json", "docs/generated/prg.rst"]
    out = subprocess.run(
        ["git", "check-ignore", "--no-index", *probes], cwd=REPO, capture_output=True, text=True
    ).stdout.split()
    assert sorted(out) == sorted(probes)
