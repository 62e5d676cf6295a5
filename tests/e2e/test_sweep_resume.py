"""Stop a `prg-train -m` sweep midway (SIGTERM on its process group), run the same command again:
the finished job is skipped, the interrupted one resumes from its last.ckpt into its own MLflow
run, and the sweep keeps one parent run — real processes, real SQLite, the basic launcher."""

import json
import os
import signal
import subprocess
import time
from pathlib import Path

import pytest
import torch
from mlflow import MlflowClient

from prg.tracking import sqlite_uri
from tests.conftest import BIN, run_cli

EPOCHS, BATCHES, EVERY = 2, 10, 2


def _args(root: Path, data_dir: Path) -> list[str]:
    return [
        "-m",
        "model=cvae",
        "seed=0,1",
        f"paths.root_dir={root}",
        f"paths.data_dir={data_dir}",
        "model.batch_size=16",
        f"trainer.max_epochs={EPOCHS}",
        f"trainer.limit_train_batches={BATCHES}",
        "trainer.limit_val_batches=2",
        "trainer.enable_progress_bar=false",
        f"callbacks.last.every_n_train_steps={EVERY}",
        "callbacks.figures=null",
        "log_model=false",
    ]


def _runs(root: Path):
    client = MlflowClient(sqlite_uri(root / "mlruns.db"))
    runs = client.search_runs([client.get_experiment_by_name("prg").experiment_id])
    parents = [r for r in runs if r.data.tags.get("prg.sweep") == "parent"]
    children = {r.data.tags["prg.seed"]: r for r in runs if r not in parents}
    return client, parents, children


def _files(folder: Path) -> dict[str, int]:
    """The outputs in ``folder`` (hidden files, a lock's, left out) and their mtimes."""
    return {p.name: p.stat().st_mtime_ns for p in folder.iterdir() if not p.name.startswith(".")}


def _stop_when(args: list[str], root: Path, ready) -> int:
    """Start the sweep in its own process group (as ``run_cli`` runs it); SIGTERM the group
    once ``ready()``."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "PRG_ROOT": str(root)}
    with (root / "stop.log").open("w") as out:
        proc = subprocess.Popen(
            [str(BIN / "prg-train"), *args],
            stdout=out,
            stderr=out,
            env=env,
            cwd=root,
            start_new_session=True,
        )
    try:
        deadline = time.monotonic() + 300  # generous: the machine may be busy
        while not ready():
            assert proc.poll() is None, f"ended early:\n{(root / 'stop.log').read_text()[-3000:]}"
            assert time.monotonic() < deadline, "not ready after 300 s"
            time.sleep(0.02)
        os.killpg(proc.pid, signal.SIGTERM)
        return proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def test_stopped_sweep_run_again_skips_finished_and_resumes_interrupted(tmp_path, small_dataset):
    args = _args(tmp_path, small_dataset)
    done, cut = tmp_path / "checkpoints/prg/cvae-seed0", tmp_path / "checkpoints/prg/cvae-seed1"
    finished, last = done / "finished.json", cut / "last.ckpt"

    status = _stop_when(args, tmp_path, lambda: finished.exists() and last.exists())
    assert status == 128 + signal.SIGTERM, (tmp_path / "stop.log").read_text()[-3000:]
    stopped = torch.load(last, weights_only=False)
    step = stopped["global_step"]
    assert 0 < step < EPOCHS * BATCHES, f"seed 1 not interrupted: step {step}"
    client, parents, children = _runs(tmp_path)
    assert len(parents) == 1 and set(children) == {"0", "1"}
    assert children["0"].info.status == "FINISHED" and children["1"].info.status != "FINISHED"
    first = children["0"]
    kept = _files(done)
    assert set(kept) == {"best.ckpt", "last.ckpt", "finished.json"}
    history = [(m.step, m.value) for m in client.get_metric_history(first.info.run_id, "val/loss")]
    assert json.loads(finished.read_text())["mlflow_run_id"] == first.info.run_id

    again = run_cli("prg-train", *args, cwd=tmp_path, timeout=600)
    assert again.returncode == 0, again.stderr[-3000:]
    assert "cvae seed 0: finished before" in again.stdout
    assert f"cvae seed 1: resuming {last} at step {step}" in again.stdout

    client, parents, children = _runs(tmp_path)
    # one run per job, one parent: the earlier parent continued, not a second one
    assert len(parents) == 1 and set(children) == {"0", "1"}
    parent = parents[0]
    assert {c.data.tags["mlflow.parentRunId"] for c in children.values()} == {parent.info.run_id}
    assert parent.info.status == "FINISHED"
    assert all(c.info.status == "FINISHED" for c in children.values())
    # the finished job was not trained again: its files and its MLflow run as they were
    assert _files(done) == kept
    assert children["0"].info.end_time == first.info.end_time
    assert [
        (m.step, m.value) for m in client.get_metric_history(first.info.run_id, "val/loss")
    ] == history
    # the interrupted one went on from its checkpoint, in its own run, each epoch logged once
    run_id = children["1"].info.run_id
    assert stopped["mlflow_run_id"] == run_id
    assert torch.load(last, weights_only=False)["global_step"] == EPOCHS * BATCHES
    configs = [a.path for a in client.list_artifacts(run_id, "config")]
    assert configs == [f"config/config-resume-{step}.yaml", "config/config.yaml"]
    epoch_ends = [(e + 1) * BATCHES - 1 for e in range(EPOCHS)]
    assert [m.step for m in client.get_metric_history(run_id, "train/loss")] == epoch_ends
    assert json.loads((cut / "finished.json").read_text())["mlflow_run_id"] == run_id


@pytest.mark.slow  # about a minute: submitit starts each job (and its requeue) as a new process
def test_a_preempted_submitit_job_is_requeued_and_resumes(tmp_path, small_dataset):
    """SLURM pre-emption without SLURM: submitit's local executor, signalled as a cluster signals
    a job (``LocalJob._interrupt``: SIGUSR2), calls the launcher's ``checkpoint`` and requeues the
    job in a new process with the same overrides; that job resumes its last.ckpt."""
    import psutil

    args = [a for a in _args(tmp_path, small_dataset) if a != "seed=0,1"]
    args.append("hydra/launcher=submitit_local")
    last = tmp_path / "checkpoints/prg/cvae-seed0/last.ckpt"
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "PRG_ROOT": str(tmp_path)}
    with (tmp_path / "sweep.log").open("w") as out:
        proc = subprocess.Popen(
            [str(BIN / "prg-train"), *args], stdout=out, stderr=out, env=env, cwd=tmp_path
        )
    try:
        deadline = time.monotonic() + 300
        while not last.exists():
            assert proc.poll() is None, (tmp_path / "sweep.log").read_text()[-3000:]
            assert time.monotonic() < deadline, "no last.ckpt after 300 s"
            time.sleep(0.02)
        (job,) = [
            p
            for p in psutil.Process(proc.pid).children(recursive=True)
            if "submitit.core._submit" in " ".join(p.cmdline())
        ]
        job.send_signal(signal.SIGUSR2)  # what SLURM sends before pre-empting (submitit's)
        assert proc.wait(timeout=600) == 0, (tmp_path / "sweep.log").read_text()[-3000:]
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    logs = _job_logs(tmp_path)
    assert any("Requeued job" in line for line in logs), "submitit did not requeue the job"
    assert any("cvae seed 0: resuming" in line for line in logs), "the requeued job did not resume"
    client, parents, children = _runs(tmp_path)
    assert len(parents) == 1 and set(children) == {"0"}
    run = children["0"]
    assert run.info.status == "FINISHED"
    assert run.data.tags["mlflow.parentRunId"] == parents[0].info.run_id
    configs = [a.path for a in client.list_artifacts(run.info.run_id, "config")]
    assert len(configs) == 2 and configs[0].startswith("config/config-resume-"), configs
    assert torch.load(last, weights_only=False)["global_step"] == EPOCHS * BATCHES


def _job_logs(root: Path) -> list[str]:
    """The lines of the submitit jobs' logs (a requeued job appends to its log)."""
    logs = (root / "logs/train/multiruns").glob("*/.submitit/*/*_log.*")
    return [line for path in logs for line in path.read_text().splitlines()]
