"""Scaling out: DDP over two CPU processes, submitit jobs, a remote MLflow server, concurrent
writers on one SQLite store — all real (gloo process groups, submitit subprocesses, an
`mlflow server` on loopback)."""

import json
import math
import os
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest
from hydra import compose, initialize_config_dir
from mlflow import MlflowClient

from prg.commands.cli import config_dir
from prg.tracking import sqlite_uri
from tests.conftest import BIN, REPO, run_cli

QUICK = [
    "trainer.max_epochs=1",
    "trainer.limit_train_batches=3",
    "trainer.limit_val_batches=2",
    "trainer.enable_progress_bar=false",
    "~callbacks.figures",
]


def _paths(root: Path, data_dir: Path) -> list[str]:
    return [f"paths.root_dir={root}", f"paths.data_dir={data_dir}"]


def _runs(client: MlflowClient):
    return client.search_runs([client.get_experiment_by_name("prg").experiment_id])


def _finite_metrics(run) -> bool:
    metrics = run.data.metrics
    return {"train/loss", "val/loss"} <= set(metrics) and all(
        math.isfinite(v) for v in metrics.values()
    )


def test_ddp_on_two_cpu_processes_logs_one_run(tmp_path, small_dataset):
    export = tmp_path / "export"
    result = run_cli(
        "prg-train",
        "trainer=ddp",
        "model=cvae",
        *_paths(tmp_path, small_dataset),
        *QUICK,
        f"export_dir={export}",
        timeout=900,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    log = result.stdout + result.stderr  # Lightning's notes go to the run log (stdout)
    assert "MEMBER: 2/2" in log and "distributed_backend=gloo" in log
    assert "sync_dist=True" not in log  # epoch metrics are averaged over both ranks
    client = MlflowClient(sqlite_uri(tmp_path / "mlruns.db"))
    (run,) = _runs(client)  # rank 1 logs nothing
    assert run.info.status == "FINISHED" and _finite_metrics(run)
    assert len(client.get_metric_history(run.info.run_id, "train/loss")) == 1
    assert [a.path for a in client.list_artifacts(run.info.run_id, "checkpoints")] == [
        "checkpoints/best.ckpt"
    ]
    assert (tmp_path / "checkpoints/prg/cvae-seed0/best.ckpt").is_file()
    assert sorted(p.name for p in export.iterdir()) == ["history.csv", "metrics.json", "model.ckpt"]
    assert json.loads((export / "metrics.json").read_text())["mlflow_run_id"] == run.info.run_id
    # both ranks share rank 0's Hydra run folder
    (run_dir,) = (tmp_path / "logs/train/runs").iterdir()
    assert (run_dir / "train_ddp_process_1.log").is_file() and (run_dir / ".hydra").is_dir()


def test_submitit_local_jobs_land_under_one_parent_run(tmp_path, small_dataset):
    result = run_cli(
        "prg-train",
        "-m",
        "model=cvae,avae_ts",
        "hydra/launcher=submitit_local",
        *_paths(tmp_path, small_dataset),
        *QUICK,
        timeout=900,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    client = MlflowClient(sqlite_uri(tmp_path / "mlruns.db"))
    runs = _runs(client)
    (parent,) = [r for r in runs if r.data.tags.get("prg.sweep") == "parent"]
    children = [r for r in runs if r is not parent]
    assert {c.data.tags["prg.family"] for c in children} == {"cvae", "avae_ts"}
    assert {c.data.tags.get("mlflow.parentRunId") for c in children} == {parent.info.run_id}
    assert all(c.info.status == "FINISHED" and _finite_metrics(c) for c in children)
    # the jobs ran as submitit jobs (own processes, pickled results)
    results = list((tmp_path / "logs/train/multiruns").glob("*/.submitit/*/*_result.pkl"))
    assert len(results) == 2


def _compose_hydra(*overrides: str):
    with initialize_config_dir(config_dir=str(config_dir()), version_base="1.3"):
        return compose("train", list(overrides), return_hydra_config=True).hydra


def test_slurm_launcher_config_composes():
    launcher = _compose_hydra(
        "hydra/launcher=slurm", "hydra.launcher.partition=gpu", "hydra.launcher.tasks_per_node=4"
    ).launcher
    assert launcher._target_.endswith("submitit_launcher.SlurmLauncher")
    assert (launcher.partition, launcher.tasks_per_node) == ("gpu", 4)
    assert launcher.timeout_min > 0 and launcher.mem_gb > 0 and launcher.gpus_per_node == 1
    # the plugin's schema is strict: a misspelt key is refused
    with pytest.raises(Exception, match="partion"):
        _compose_hydra("hydra/launcher=slurm", "hydra.launcher.partion=gpu")


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@pytest.fixture
def mlflow_server(tmp_path):
    """A real `mlflow server` on loopback, SQLite backend, artifacts proxied to a folder."""
    folder = tmp_path / "server"
    folder.mkdir()
    port = _free_port()
    log = folder / "server.log"
    with open(log, "w") as out:
        server = subprocess.Popen(
            [
                str(BIN / "mlflow"),
                "server",
                "--host=127.0.0.1",
                f"--port={port}",
                f"--backend-store-uri=sqlite:///{folder / 'server.db'}",
                f"--artifacts-destination={folder / 'artifacts'}",
                "--workers=1",
            ],
            stdout=out,
            stderr=subprocess.STDOUT,
            cwd=folder,
            start_new_session=True,  # its own process group: the server and its workers
        )
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 240
        while True:
            assert server.poll() is None, log.read_text()[-3000:]
            try:
                with urllib.request.urlopen(f"{url}/health", timeout=5) as reply:
                    if reply.status == 200:
                        break
            except OSError:
                pass
            assert time.monotonic() < deadline, "mlflow server did not answer /health"
            time.sleep(1)
        yield url, folder
    finally:
        os.killpg(server.pid, signal.SIGTERM)
        try:
            server.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(server.pid, signal.SIGKILL)
            server.wait()


def test_runs_and_artifacts_go_through_a_tracking_server(tmp_path, small_dataset, mlflow_server):
    url, folder = mlflow_server
    result = run_cli(
        "prg-train",
        "model=cvae",
        *_paths(tmp_path, small_dataset),
        *QUICK,
        f"logger.tracking_uri={url}",
        timeout=600,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    client = MlflowClient(url)
    experiment = client.get_experiment_by_name("prg")
    assert experiment.artifact_location.startswith("mlflow-artifacts:")  # the server's, proxied
    (run,) = client.search_runs([experiment.experiment_id])
    assert run.info.status == "FINISHED" and _finite_metrics(run)
    assert run.data.params["model.name"] == "cvae"
    stored = folder / "artifacts" / experiment.experiment_id / run.info.run_id / "artifacts"
    for path in ("config/config.yaml", "checkpoints/best.ckpt"):
        assert (stored / path).is_file(), path
    assert "model:" in (stored / "config/config.yaml").read_text()
    # nothing was written to the local store
    assert not (tmp_path / "mlruns.db").exists() and not (tmp_path / "mlartifacts").exists()


WRITER = """
import sys
from prg.tracking import get_experiment_id, mlflow_client
client = mlflow_client(sys.argv[1])
experiment = get_experiment_id(client, "prg", sys.argv[2])
run = client.create_run(experiment)
for step in range(20):
    client.log_metric(run.info.run_id, "m", step, step=step)
client.set_terminated(run.info.run_id)
"""


def test_processes_sharing_a_new_sqlite_store(tmp_path):
    """Four processes start on a store that does not exist yet: one creates the tables (the
    others wait for it: MLflow alone fails with "duplicate column name"), all log."""
    uri = sqlite_uri(tmp_path / "mlruns.db")
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    writers = [
        subprocess.Popen(
            [sys.executable, "-c", WRITER, uri, (tmp_path / "artifacts").as_uri()],
            env=env,
            stderr=subprocess.PIPE,
            text=True,
        )
        for _ in range(4)
    ]
    errors = [w.communicate(timeout=600)[1] for w in writers]
    assert [w.returncode for w in writers] == [0] * 4, "\n".join(errors)[-3000:]
    assert not any("locked" in e for e in errors)
    runs = _runs(MlflowClient(uri))
    assert len(runs) == 4 and all(r.info.status == "FINISHED" for r in runs)
    assert all(r.data.metrics["m"] == 19 for r in runs)
