"""What a reviewer meets in the MLflow UI, on a real SQLite store after a real (tiny) training:
experiment kinds, training and task experiments, curves every few steps, run descriptions, the
metric shared by every family, readable generation figures, and moving a store."""

from __future__ import annotations

import hashlib
import math
import shutil
from pathlib import Path

import lightning as L
import numpy as np
import pytest
import torch
from hydra.utils import instantiate
from mlflow import MlflowClient
from omegaconf import OmegaConf
from PIL import Image

from prg.alphabet import ALPHABET
from prg.commands.cli import compose_config
from prg.commands.train import build_datamodule, train
from prg.data.store import load_split
from prg.tracking import (
    DESCRIPTION_TAG,
    EXPERIMENT_KIND,
    get_experiment_id,
    main,
    mlflow_client,
    move_store,
    sqlite_uri,
    task_run,
)
from prg.training.callbacks import GenerationFigures, TrajectoryNLL

EVERY = 1  # trainer.log_every_n_steps in the run below
EPOCHS, BATCHES = 2, 2


@pytest.fixture(scope="module")
def trained(tmp_path_factory, small_dataset):
    """A tiny AVAE(T,S) training and a task run in one store: (root, result, client)."""
    root = tmp_path_factory.mktemp("root")
    cfg = compose_config(
        "train",
        [
            f"paths.root_dir={root}",
            f"paths.data_dir={small_dataset}",
            "model=avae_ts",
            f"trainer.max_epochs={EPOCHS}",
            f"trainer.limit_train_batches={BATCHES}",
            "trainer.limit_val_batches=1",
            "trainer.enable_progress_bar=false",
            f"trainer.log_every_n_steps={EVERY}",
            "callbacks.figures.every_n_epochs=100",  # the final figures only
            "callbacks.figures.n_examples=6",
        ],
    )
    result = train(cfg)
    write_cfg = compose_config("write", [f"paths.root_dir={root}"])
    with task_run(write_cfg, "write", {"prg.family": "avae_ts"}) as run:
        run.log_metrics({"points": 7}, prefix="write/")
    return root, result, MlflowClient(sqlite_uri(root / "mlruns.db"))


def test_training_and_task_runs_land_in_their_own_experiments_of_the_training_kind(trained):
    _, result, client = trained
    training = client.get_experiment_by_name("prg")
    tasks = client.get_experiment_by_name("prg-tasks")
    assert client.get_run(result.run_id).info.experiment_id == training.experiment_id
    (task,) = client.search_runs([tasks.experiment_id])
    assert task.data.tags["prg.task"] == "write"
    assert [r.info.run_id for r in client.search_runs([training.experiment_id])] == [result.run_id]
    for experiment in (training, tasks):
        assert experiment.tags["mlflow.experimentKind"] == "custom_model_development"


def test_an_experiment_without_a_kind_gets_one_and_a_kind_picked_in_the_ui_stays(trained):
    root, _, _ = trained
    client = mlflow_client(sqlite_uri(root / "mlruns.db"))
    bare = client.create_experiment("old", artifact_location=(root / "old").as_uri())
    picked = client.create_experiment("picked", tags={"mlflow.experimentKind": "genai_development"})
    assert get_experiment_id(client, "old", None) == bare
    get_experiment_id(client, "picked", None)
    assert client.get_experiment(bare).tags == EXPERIMENT_KIND
    assert client.get_experiment(picked).tags["mlflow.experimentKind"] == "genai_development"
    for experiment in (bare, picked):
        client.delete_experiment(experiment)


def test_curves_have_a_point_every_n_steps_averaging_those_steps(trained):
    _, result, client = trained
    steps = [m for m in client.get_metric_history(result.run_id, "train_steps/loss")]
    epochs = client.get_metric_history(result.run_id, "train/loss")
    assert len(epochs) == EPOCHS
    assert [m.step for m in steps] == list(range(EVERY - 1, EPOCHS * BATCHES, EVERY))
    # equal batches: each epoch's mean is the mean of its steps' windows
    for e, epoch in enumerate(epochs):
        window = [m.value for m in steps if e * BATCHES <= m.step < (e + 1) * BATCHES]
        assert epoch.step == (e + 1) * BATCHES - 1
        assert epoch.value == pytest.approx(np.mean(window), rel=1e-5)


def test_metric_names_use_the_papers_letters_and_dvc_keys_are_unchanged(trained):
    _, result, client = trained
    logged = set(client.get_run(result.run_id).data.metrics)
    assert {"train/rec_T", "train/kl_S", "val/rec_S", "train_steps/kl_T"} <= logged
    assert not [k for k in logged if any(m in k for m in ("traj", "label", "image"))]
    assert "train/rec_traj" in result.metrics  # the trainer's (and metrics.json's) names


def test_the_run_describes_itself(trained, small_dataset):
    _, result, client = trained
    note = client.get_run(result.run_id).data.tags[DESCRIPTION_TAG]
    manifest = (small_dataset / "prepared/synthetic/manifest.json").read_bytes()
    for part in ("PRG_AVAE(T,S)", "`avae_ts`", "profile `default`", "Data: `synthetic`"):
        assert part in note
    assert hashlib.sha256(manifest).hexdigest()[:12] in note
    assert "prg-train" in note and f"every {EVERY} steps" in note
    task = client.search_runs([client.get_experiment_by_name("prg-tasks").experiment_id])[0]
    assert "prg-write" in task.data.tags[DESCRIPTION_TAG]
    assert "avae_ts" in task.data.tags[DESCRIPTION_TAG]


def test_the_trajectory_nll_is_logged_at_each_validation(trained):
    _, result, client = trained
    history = client.get_metric_history(result.run_id, "val/nll_per_dim_T")
    assert [m.step for m in history] == [(e + 1) * BATCHES - 1 for e in range(EPOCHS)]
    assert all(math.isfinite(m.value) for m in history)


@pytest.mark.parametrize("family", ["cvae", "avae_ts", "avae_ti", "muse"])
def test_every_family_logs_the_trajectory_nll_of_its_reconstruction(family, small_dataset):
    cfg = compose_config(
        "train", [f"paths.data_dir={small_dataset}", f"model={family}", "model.batch_size=16"]
    )
    torch.manual_seed(0)
    module = instantiate(OmegaConf.to_container(cfg.model.module, resolve=True), _recursive_=False)
    datamodule = build_datamodule(cfg)
    trainer = L.Trainer(
        accelerator="cpu",
        limit_val_batches=1,
        logger=False,
        enable_progress_bar=False,
        enable_model_summary=False,
        callbacks=[TrajectoryNLL()],
    )
    (logged,) = trainer.validate(module, datamodule=datamodule, verbose=False)
    # by hand: the posterior mean's squared error under N(mean, traj_std^2), per coordinate
    batch = next(iter(datamodule.val_dataloader()))
    given = {"cvae": ("traj", "label")}.get(family, ("traj",))
    module.eval()
    mean = module.model.generate({m: batch[m] for m in given}, "traj")[0]
    std = cfg.model.module.model.traj_std
    squared = ((mean - batch["traj"]) ** 2).mean()
    expected = squared / (2 * std**2) + math.log(std * math.sqrt(2 * math.pi))
    assert logged[TrajectoryNLL.KEY] == pytest.approx(float(expected), rel=1e-4)


def test_figures_are_readable_and_show_classes_across_the_alphabet(trained, small_dataset):
    _, result, client = trained
    (figures,) = [c for c in result.trainer.callbacks if isinstance(c, GenerationFigures)]
    labels = load_split(small_dataset / "prepared/synthetic/val.npz")["label"]
    shown = [ALPHABET[int(labels[i])] for i in figures.example_indices]
    assert shown == figures.example_classes and len(set(shown)) == 6
    assert any(c.isdigit() for c in shown) and any(c.isupper() for c in shown)
    assert any(c.islower() for c in shown)
    assert shown == sorted(shown, key=ALPHABET.index)  # spread in class order
    local = client.download_artifacts(result.run_id, "figures/final/recon_traj.png")
    with Image.open(local) as image:
        assert all(round(d) >= 150 for d in image.info["dpi"])
        assert image.width >= 6 * 0.7 * 150  # six columns of 0.7 inch


def test_a_moved_store_is_re_pointed(trained, tmp_path):
    root, result, _ = trained
    moved = shutil.copytree(root, tmp_path / "moved")  # the checkout, elsewhere
    before, after = root / "mlartifacts", moved / "mlartifacts"

    # the two experiments' locations, the two runs' and the training run's logged model's
    assert move_store(moved / "mlruns.db", before, after) == 5
    client = MlflowClient(sqlite_uri(moved / "mlruns.db"))
    run = client.get_run(result.run_id)
    model_id = run.data.tags["prg.model_uri"].removeprefix("models:/")
    assert client.get_logged_model(model_id).artifact_location.startswith(after.as_uri())
    assert run.info.artifact_uri == f"{after.as_uri()}/{result.run_id}/artifacts"
    assert client.get_experiment(run.info.experiment_id).artifact_location == after.as_uri()
    config = after / result.run_id / "artifacts/config/config.yaml"
    config.write_text(config.read_text() + "# the moved copy\n")  # told apart from the original
    local = client.download_artifacts(result.run_id, "config/config.yaml", str(tmp_path))
    assert Path(local).read_text().endswith("# the moved copy\n")
    assert move_store(moved / "mlruns.db", before, after) == 0  # nothing left to re-point


@pytest.mark.parametrize(
    "argv, expected",
    [
        (["move-store", "nothing.db", "/old", "."], "store nothing.db: no such file"),
        (["move-store"], "usage: python -m prg.tracking move-store DB"),
        (["move-store", "{db}", "/old", "/no/such/folder"], "no such folder"),
        (["move-store", "{db}", "/old", "{tmp}"], "not an MLflow SQLite store"),
    ],
)
def test_moving_a_store_refuses_bad_input_in_one_line(tmp_path, capsys, argv, expected):
    db = tmp_path / "not-mlflow.db"
    db.write_bytes(b"")
    code = main([a.format(db=db, tmp=tmp_path) for a in argv])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and expected in err[0], err
