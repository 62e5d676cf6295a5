"""Helpers shared by the tests that were split out of tests/test_train.py."""

from pathlib import Path

from mlflow import MlflowClient

from prg.commands.cli import compose_config
from prg.tracking import sqlite_uri

FAST = [
    "trainer.max_epochs=2",
    "trainer.limit_train_batches=3",
    "trainer.limit_val_batches=2",
    "trainer.enable_progress_bar=false",
    "callbacks.figures.every_n_epochs=1",
    "callbacks.figures.n_examples=4",
]


def _cfg(tmp_path: Path, data_dir: Path, *overrides: str):
    return compose_config(
        "train", [f"paths.root_dir={tmp_path}", f"paths.data_dir={data_dir}", *FAST, *overrides]
    )


def _client(root: Path) -> MlflowClient:
    return MlflowClient(sqlite_uri(root / "mlruns.db"))
