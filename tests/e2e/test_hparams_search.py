"""`prg-train hparams_search=<family>_optuna`: an Optuna search as a Hydra multirun (the
prg_optuna sweeper in src/hydra_plugins/), its trials under one MLflow parent run, its study in
an SQLite storage that a real optuna-dashboard serves."""

from __future__ import annotations

import json
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import optuna
import pytest
import yaml
from mlflow import MlflowClient

from prg.commands.cli import compose_config
from prg.tracking import sqlite_uri
from tests.conftest import run_cli

BIN = Path(sys.executable).parent
FAMILIES = ["cvae", "avae_ts", "avae_ti", "muse"]


@pytest.mark.parametrize("family", FAMILIES)
def test_each_family_has_a_search_over_the_recipes_knobs(family):
    cfg = compose_config("train", [f"hparams_search={family}_optuna"], hydra_config=True)
    sweeper = cfg.hydra.sweeper
    assert sweeper._target_.endswith("PRGOptunaSweeper") and cfg.model.name == family
    assert cfg.profile == "quick" and sweeper.objective == "val/loss"
    assert {"model.module.optimizer.lr", "model.batch_size"} <= set(sweeper.params)
    assert sweeper.storage.startswith("sqlite:///")


@pytest.fixture(scope="module")
def search(tmp_path_factory, small_dataset):
    root = tmp_path_factory.mktemp("search")
    result = run_cli(
        "prg-train",
        "hparams_search=cvae_optuna",
        "hydra.sweeper.n_trials=2",
        "hydra.sweeper.n_startup_trials=1",
        f"paths.root_dir={root}",
        f"paths.data_dir={small_dataset}",
        "trainer.max_epochs=1",
        "trainer.limit_train_batches=3",
        "trainer.limit_val_batches=2",
        "trainer.enable_progress_bar=false",
        "callbacks.figures=null",
        "log_model=false",
        cwd=root,
        timeout=600,
    )
    assert result.returncode == 0, result.stderr[-4000:]
    return root


def test_two_trials_land_in_the_optuna_storage_with_their_objective(search):
    study = optuna.load_study(study_name="cvae-quick", storage=f"sqlite:///{search}/optuna.db")
    complete = [t for t in study.trials if t.state == optuna.trial.TrialState.COMPLETE]
    assert len(complete) == 2
    for trial in complete:
        assert 5e-4 <= trial.params["model.module.optimizer.lr"] <= 5e-3
        assert trial.params["model.batch_size"] in (64, 128, 256)
    (results,) = search.glob("logs/train/multiruns/*/optimization_results.yaml")
    best = yaml.safe_load(results.read_text())
    assert best["best_value"] == pytest.approx(study.best_value)
    assert best["best_params"] == study.best_params


def test_the_trials_are_children_of_one_mlflow_parent_run(search):
    client = MlflowClient(sqlite_uri(search / "mlruns.db"))
    experiment = client.get_experiment_by_name("prg")
    runs = client.search_runs([experiment.experiment_id])
    parents = [r for r in runs if r.data.tags.get("prg.sweep") == "parent"]
    assert len(parents) == 1
    children = [r for r in runs if r.data.tags.get("mlflow.parentRunId") == parents[0].info.run_id]
    assert len(children) == 2
    study = optuna.load_study(study_name="cvae-quick", storage=f"sqlite:///{search}/optuna.db")
    logged = sorted(r.data.metrics["val/loss"] for r in children)
    told = sorted(t.value for t in study.trials)
    assert logged == pytest.approx(told, rel=1e-5)  # each trial's objective is its run's val/loss
    lrs = sorted(float(r.data.params["model.module.optimizer.lr"]) for r in children)
    assert lrs == pytest.approx(sorted(t.params["model.module.optimizer.lr"] for t in study.trials))


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_optuna_dashboard_opens_the_study(search):
    port = _free_port()
    server = subprocess.Popen(
        [
            str(BIN / "optuna-dashboard"),
            f"sqlite:///{search}/optuna.db",
            "--host",
            "127.0.0.1",
            "--port",
            str(port),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/studies", timeout=2) as r:
                    studies = json.loads(r.read())["study_summaries"]
                    break
            except (urllib.error.URLError, ConnectionError, TimeoutError):
                assert server.poll() is None, server.stdout.read()[-3000:]
                assert time.monotonic() < deadline, "optuna-dashboard did not start in 60 s"
                time.sleep(0.5)
    finally:
        server.terminate()
        server.wait(timeout=30)
    (study,) = [s for s in studies if s["study_name"] == "cvae-quick"]
    assert study["directions"] == ["minimize"]


def test_a_search_without_parameters_is_refused(tmp_path, small_dataset):
    result = run_cli(
        "prg-train",
        "-m",
        "hydra/sweeper=prg_optuna",
        f"paths.root_dir={tmp_path}",
        f"paths.data_dir={small_dataset}",
        cwd=tmp_path,
    )
    assert result.returncode != 0
    output = result.stderr + result.stdout
    assert "the Optuna sweeper has nothing to search" in output and "Traceback" not in output
