"""Helpers shared by the tests that were split out of tests/test_serving.py."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from prg.commands.cli import compose_config
from prg.commands.train import train
from prg.tracking import sqlite_uri
from prg.writer import Writer


def _train_muse(root: Path, data_dir: Path, seed: int):
    """A MUSE trained for a few steps into ``root``'s store, exported to ``models/muse`` (seed
    0) or ``models/muse-<seed>``."""
    cfg = compose_config(
        "train",
        [
            "model=muse",
            f"seed={seed}",
            f"paths.root_dir={root}",
            f"paths.data_dir={data_dir}",
            f"export_dir={root / 'models' / ('muse' if seed == 0 else f'muse-{seed}')}",
            "trainer.max_epochs=1",
            "trainer.limit_train_batches=3",
            "trainer.limit_val_batches=2",
            "trainer.enable_progress_bar=false",
            "callbacks.figures=null",
        ],
    )
    return train(cfg)


@pytest.fixture(scope="module")
def trained(tmp_path_factory, small_dataset):
    """A MUSE trained for a few steps, exported, its best checkpoint logged as an MLflow model."""
    root = tmp_path_factory.mktemp("serving")
    result = _train_muse(root, small_dataset, seed=0)
    uri = sqlite_uri(root / "mlruns.db")
    return {"root": root, "uri": uri, "run_id": result.run_id, "ckpt": result.best_checkpoint}


def library_rollout(ckpt: str, **write) -> np.ndarray:
    return Writer.from_checkpoint(ckpt).write(**write).rollout
