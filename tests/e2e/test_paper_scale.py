"""``python -m prg.commands.paper_scale`` (``make paper``): the whole path on the CPU with a tiny budget —
four concurrent trainings and the classifiers, then the evaluation into its own folder — and its
failures: bad options (one line, exit 2, nothing started) and a training that fails (one line,
exit 1, the other processes stopped)."""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from mlflow import MlflowClient

from prg.commands import paper_scale
from prg.tracking import sqlite_uri

TINY = [
    "--device",
    "cpu",
    "--epochs",
    "1",
    "--limit-train-batches",
    "2",
    "--limit-val-batches",
    "1",
    "--k-marginal",
    "2",
    "--k-conditional",
    "3",
    "--progress-every",
    "2",
    "--train-set",
    "callbacks.figures=null",
    "--eval-set",
    "figures=false",
    "--eval-set",
    "classifier.epochs=1",
]


def _run(cwd: Path, *args: str, timeout: int = 600) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "MLFLOW_TRACKING_URI"}
    return subprocess.run(
        [sys.executable, "-m", "prg.commands.paper_scale", *args],
        cwd=cwd,
        env={**env, "PYTHONUNBUFFERED": "1", "PRG_ROOT": str(cwd)},  # its store: cwd's
        capture_output=True,
        text=True,
        timeout=timeout,
    )


@pytest.mark.slow  # four trainings and an evaluation: 2.5-5 min of both cores (make test-all)
def test_trains_four_families_concurrently_then_evaluates_into_its_own_folder(
    tmp_path, small_dataset
):
    result = _run(tmp_path, *TINY, "--data-dir", str(small_dataset))
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr
    assert result.stderr == ""
    out = result.stdout
    for job in (*paper_scale.FAMILIES, "classifiers", "evaluate"):
        assert f"[{job}] start: " in out and f"[{job}] done in " in out
    assert "[muse] Epoch 0: " in out  # its progress bar, shortened, with the name in front

    root = tmp_path / "paper"
    reports = root / "reports"
    table1 = (reports / "table1.md").read_text()
    rows = list(csv.DictReader((reports / "table1.csv").open()))
    assert {r["family"] for r in rows} == set(paper_scale.FAMILIES)
    assert {int(r["k"]) for r in rows} == {2, 3}  # --k-marginal / --k-conditional
    n_test = len(np.load(small_dataset / "prepared/synthetic/test.npz")["label"])
    assert {int(r["n_test"]) for r in rows} == {n_test}  # the whole test split
    for title in ("PRG_CVAE(T,S)", "PRG_AVAE(T,S)", "PRG_AVAE(T,I)", "PRG_MUSE(T,S,I)"):
        assert title in table1
        assert title in (reports / "coherence.md").read_text()
    assert (reports / "robustness.md").is_file()
    for family in paper_scale.FAMILIES:
        assert (root / "models" / family / "model.ckpt").is_file()
        assert (root / "checkpoints" / family / "last.ckpt").is_file()
        assert (root / "logs" / f"train-{family}.log").stat().st_size > 0
    assert {p.name for p in (root / "models" / "classifiers").glob("*.pt")} == {
        "traj.pt",
        "image.pt",
    }
    # the demo's folders are untouched (not even created)
    assert not (tmp_path / "models").exists() and not (tmp_path / "reports").exists()
    assert not (tmp_path / "checkpoints").exists()

    timings = json.loads((reports / "paper_scale.json").read_text())
    assert timings["status"] == "ok" and timings["accelerator"] == "cpu"
    assert "cores)" in timings["device"]  # the CPU's name when there is no GPU
    assert set(timings["stages"]) == {"train", "evaluate"}  # the dataset was there
    train = timings["stages"]["train"]
    assert set(train["jobs"]) == {*paper_scale.FAMILIES, "classifiers"}
    # concurrent: the stage lasts about as long as its longest job, not their sum
    assert max(train["jobs"].values()) <= train["seconds"] < sum(train["jobs"].values())
    assert timings["stages"]["evaluate"]["seconds"] > 0
    assert timings["total_seconds"] >= train["seconds"] + timings["stages"]["evaluate"]["seconds"]
    settings = timings["settings"]
    assert settings["max_epochs"] == 1 and settings["precision"] == "32-true"
    assert settings["lr"] == dict.fromkeys(paper_scale.FAMILIES, 0.0001)  # the paper's Adam
    assert settings["batch_size"] == {"cvae": 128, "avae_ts": 128, "avae_ti": 128, "muse": 64}
    assert (settings["k_marginal"], settings["k_conditional"], settings["n_test"]) == (2, 3, None)
    for path in timings["reports"].values():
        assert (tmp_path / path).is_file()
        assert f"{path}" in out  # printed at the end
    assert f"Timings:    {reports.relative_to(tmp_path) / 'paper_scale.json'}" in out

    client = MlflowClient(sqlite_uri(tmp_path / "mlruns.db"))
    training, tasks = (client.get_experiment_by_name(n) for n in ("prg-paper", "prg-paper-tasks"))
    runs = client.search_runs([training.experiment_id, tasks.experiment_id])
    assert sorted(r.info.run_name for r in runs) == sorted(
        [f"{f}-seed0" for f in paper_scale.FAMILIES] + ["paper-evaluate"]
    )
    (evaluate,) = client.search_runs([tasks.experiment_id])  # task runs in their own experiment
    assert evaluate.info.run_name == "paper-evaluate"
    assert all(r.info.status == "FINISHED" for r in runs)
    assert all(r.data.tags.get("prg.experiment") == "paper" for r in runs)


def test_a_failed_training_stops_the_others_and_fails_with_one_line(tmp_path, small_dataset):
    root = tmp_path / "paper"  # absolute, so that the children are found by their command lines
    start = time.monotonic()
    result = _run(
        tmp_path,
        *TINY,
        "--data-dir",
        str(small_dataset),
        "--root",
        str(root),
        "--families",
        "cvae,muse",
        "--train-set",
        "cvae:model.module.optimizer.lr=-1",  # prg-train refuses it (prg.checks), exit 2
        "--train-set",
        "muse:trainer.max_epochs=100000",  # would run far longer than this test
    )
    elapsed = time.monotonic() - start
    assert result.returncode == 2, result.stdout[-3000:] + result.stderr
    (line,) = result.stderr.splitlines()
    assert line.startswith("prg.commands.paper_scale: error: train: cvae failed (exit 2): ")
    assert "model.module.optimizer.lr must be a finite number in (0, 10], got -1" in line
    assert "stopped muse" in line and f"log: {root / 'logs' / 'train-cvae.log'}" in line
    assert elapsed < 120
    survivors = []
    for cmdline in Path("/proc").glob("[0-9]*/cmdline"):
        try:
            if str(root).encode() in cmdline.read_bytes():
                survivors.append(cmdline.parent.name)
        except OSError:
            pass  # a process that ended meanwhile
    assert survivors == []
    assert not (root / "reports" / "table1.md").exists()
    assert not (root / "models" / "cvae" / "model.ckpt").exists()
    assert not (root / "reports" / "paper_scale.json").exists()  # only complete runs' records
    timings = json.loads((root / "logs" / "paper_scale.json").read_text())
    assert timings["status"].startswith("failed: train: cvae failed")
    assert "evaluate" not in timings["stages"]
    assert set(timings["stages"]["train"]["jobs"]) == {"cvae", "muse", "classifiers"}


@pytest.mark.slow  # 140 s; the runner itself is tested above, this is its second profile
def test_the_converged_profile_trains_the_fast_recipe_into_its_own_folder(tmp_path, small_dataset):
    result = _run(
        tmp_path,
        *TINY,
        "--data-dir",
        str(small_dataset),
        "--profile",
        "converged",
        "--families",
        "cvae,muse",
        "--n-test-likelihood",
        "5",
    )
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr
    assert "Profile converged done in " in result.stdout
    root = tmp_path / "converged"
    timings = json.loads((root / "reports/paper_scale.json").read_text())
    assert timings["profile"] == "converged" and timings["status"] == "ok"
    settings = timings["settings"]
    assert settings["precision"] == "bf16-mixed"  # the fast recipe, not the paper's
    assert settings["lr"] == {"cvae": 0.002, "muse": 0.002}
    assert settings["batch_size"] == {"cvae": 128, "muse": 128}
    fit = timings["fit"]
    assert set(fit) == {"cvae", "muse"}
    for family, cost in fit.items():
        metrics = json.loads((root / "models" / family / "metrics.json").read_text())
        assert cost["fit_cpu_s"] == metrics["fit_cpu_s"] > 0
        assert cost["steps"] == metrics["steps"] == 2  # --limit-train-batches 2, one epoch
    rows = list(csv.DictReader((root / "reports/table1.csv").open()))
    assert {int(r["n_test"]) for r in rows} == {5}  # Table I on 5 samples ...
    n_test = len(np.load(small_dataset / "prepared/synthetic/test.npz")["label"])
    coherence = list(csv.DictReader((root / "reports/coherence.csv").open()))
    assert {int(r["n"]) for r in coherence} == {n_test}  # ... coherence on all of them
    client = MlflowClient(sqlite_uri(tmp_path / "mlruns.db"))
    runs = client.search_runs(
        [
            client.get_experiment_by_name(n).experiment_id
            for n in ("prg-converged", "prg-converged-tasks")
        ]
    )
    assert sorted(r.info.run_name for r in runs) == [
        "converged-evaluate",
        "cvae-seed0",
        "muse-seed0",
    ]
    assert all(r.data.tags.get("prg.experiment") == "converged" for r in runs)
    assert not (tmp_path / "paper").exists()
