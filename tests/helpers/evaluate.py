"""Helpers shared by the tests that were split out of tests/test_evaluate.py."""

from pathlib import Path

import pytest

from prg.commands.cli import compose_config
from prg.commands.train import train

FAMILIES = ("cvae", "avae_ts", "avae_ti", "muse")


TINY = [
    "likelihood.k_marginal=4",
    "likelihood.k_conditional=6",
    "likelihood.n_test=12",
    "classifier.epochs=1",
    "kinematics.words=[ab]",
    "progress=false",
]


@pytest.fixture(scope="module")
def trained_root(tmp_path_factory, small_dataset) -> Path:
    """A project root whose models/<family>/model.ckpt hold briefly trained models."""
    root = tmp_path_factory.mktemp("root")
    for family in FAMILIES:
        cfg = compose_config(
            "train",
            [
                f"paths.root_dir={root}",
                f"paths.data_dir={small_dataset}",
                f"model={family}",
                "trainer.max_epochs=1",
                "trainer.limit_train_batches=2",
                "trainer.limit_val_batches=1",
                "trainer.enable_progress_bar=false",
                "callbacks.figures.every_n_epochs=100",
                f"export_dir={root}/models/{family}",
            ],
        )
        train(cfg)
    return root


def _cfg(root: Path, data_dir: Path, *overrides: str):
    return compose_config(
        "evaluate", [f"paths.root_dir={root}", f"paths.data_dir={data_dir}", *TINY, *overrides]
    )
