"""Kill `prg-train` mid-epoch (SIGKILL), resume with `ckpt_path=last`: the run finishes, MLflow
shows one run, FINISHED, with every epoch logged once, and the weights and losses are those of
an uninterrupted run — real processes, real SQLite."""

import os
import signal
import subprocess
import time
from pathlib import Path

import torch
from mlflow import MlflowClient

from prg.tracking import sqlite_uri
from tests.conftest import BIN, run_cli

EPOCHS, BATCHES, EVERY, BATCH_SIZE = 2, 10, 2, 16  # the first save leaves 8 steps of margin


def _args(root: Path, data_dir: Path) -> list[str]:
    return [
        f"paths.root_dir={root}",
        f"paths.data_dir={data_dir}",
        "model=cvae",
        f"model.batch_size={BATCH_SIZE}",
        f"trainer.max_epochs={EPOCHS}",
        f"trainer.limit_train_batches={BATCHES}",
        "trainer.limit_val_batches=2",
        "trainer.enable_progress_bar=false",
        f"callbacks.last.every_n_train_steps={EVERY}",
        "callbacks.figures=null",
    ]


def _runs(root: Path):
    client = MlflowClient(sqlite_uri(root / "mlruns.db"))
    return client, client.search_runs([client.get_experiment_by_name("prg").experiment_id])


def _start_and_kill_after_first_checkpoint(args: list[str], last: Path, log: Path) -> int:
    """Start prg-train, SIGKILL it as soon as last.ckpt exists; returns its exit status."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    with log.open("w") as out:
        proc = subprocess.Popen([str(BIN / "prg-train"), *args], stdout=out, stderr=out, env=env)
    try:
        deadline = time.monotonic() + 300  # generous: the machine may be busy
        while not last.exists():
            assert proc.poll() is None, f"prg-train ended before a checkpoint:\n{log.read_text()}"
            assert time.monotonic() < deadline, "no last.ckpt after 300 s"
            time.sleep(0.02)
        os.kill(proc.pid, signal.SIGKILL)
        return proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_killed_mid_epoch_run_resumes_into_one_finished_run(tmp_path, small_dataset):
    args = _args(tmp_path, small_dataset)
    ckpt_dir = tmp_path / "checkpoints/prg/cvae-seed0"
    last = ckpt_dir / "last.ckpt"

    status = _start_and_kill_after_first_checkpoint(args, last, tmp_path / "killed.log")
    assert status == -signal.SIGKILL
    killed = torch.load(last, weights_only=False)
    step = killed["global_step"]
    assert 0 < step < EPOCHS * BATCHES and step % BATCHES, f"not mid-epoch: step {step}"
    assert killed["prg_epoch_sums"]["counts"]["train"] == (step % BATCHES) * BATCH_SIZE
    client, runs = _runs(tmp_path)
    assert len(runs) == 1 and runs[0].info.status == "RUNNING"  # what a kill leaves
    run_id = runs[0].info.run_id
    assert killed["mlflow_run_id"] == run_id

    result = run_cli("prg-train", *args, "ckpt_path=last", timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]

    client, runs = _runs(tmp_path)
    assert [r.info.run_id for r in runs] == [run_id]
    assert runs[0].info.status == "FINISHED"
    assert torch.load(last, weights_only=False)["global_step"] == EPOCHS * BATCHES
    outputs = {p.name for p in ckpt_dir.iterdir() if not p.name.startswith(".")}
    assert outputs == {"best.ckpt", "last.ckpt", "finished.json"}  # finished.json: resume=auto
    epoch_ends = [(e + 1) * BATCHES - 1 for e in range(EPOCHS)]  # each epoch once, at its end
    for name in ("train/loss", "val/loss"):
        assert [m.step for m in client.get_metric_history(run_id, name)] == epoch_ends, name
    epochs = client.get_metric_history(run_id, "epoch")
    assert sorted({(m.step, m.value) for m in epochs}) == [(s, e) for e, s in enumerate(epoch_ends)]
    configs = [a.path for a in client.list_artifacts(run_id, "config")]
    assert configs == [f"config/config-resume-{step}.yaml", "config/config.yaml"]

    # the same training without a stop: the same batches in the same order, the same noise
    whole = tmp_path / "whole"
    result = run_cli("prg-train", *_args(whole, small_dataset), timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]
    resumed = torch.load(last, weights_only=False)["state_dict"]
    uninterrupted = torch.load(whole / "checkpoints/prg/cvae-seed0/last.ckpt", weights_only=False)[
        "state_dict"
    ]
    assert resumed.keys() == uninterrupted.keys()
    different = [k for k in resumed if not torch.equal(resumed[k], uninterrupted[k])]
    assert not different, f"resumed weights differ from an uninterrupted run's: {different[:5]}"
    whole_client, (whole_run,) = _runs(whole)
    for name in ("train/loss", "val/loss"):
        losses = [m.value for m in client.get_metric_history(run_id, name)]
        assert losses == [
            m.value for m in whole_client.get_metric_history(whole_run.info.run_id, name)
        ], name


def test_ckpt_path_last_without_a_checkpoint_is_one_line_exit_2(tmp_path, small_dataset):
    result = run_cli("prg-train", *_args(tmp_path, small_dataset), "ckpt_path=last")
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2, result.stderr[-2000:]
    assert len(lines) == 1 and lines[0].startswith("prg-train: error: ckpt_path=last"), lines
    assert "checkpoints/prg/cvae-seed0/last.ckpt" in lines[0]
