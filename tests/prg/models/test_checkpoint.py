"""Tests of ``prg.models.checkpoint`` (moved from the suite on: a checkpoint is data: opening one
never runs code, and it may only name the project's models and torch's optimizers and schedulers
to build)."""

from __future__ import annotations

import pytest
import torch

from prg.errors import UsageError
from prg.evaluation.coherence import coherence_cells
from prg.models.checkpoint import check_targets, load_model, read_checkpoint
from tests.helpers.checkpoint_trust import _hostile_pickle
from tests.helpers.evaluate import FAMILIES, trained_root  # noqa: F401 (fixtures)


def _checkpoint_naming(path, target: str) -> None:
    model = {"_target_": target, "command": "echo hi"}
    torch.save({"state_dict": {}, "hyper_parameters": {"model": model}}, path)


def test_a_checkpoint_whose_pickle_runs_code_is_refused_and_runs_nothing(tmp_path):
    marker = tmp_path / "pwned"
    ckpt = tmp_path / "evil.ckpt"
    _hostile_pickle(ckpt, marker)
    for load in (read_checkpoint, load_model):
        with pytest.raises(UsageError, match=r"refused: it holds a posix.system object"):
            load(ckpt)
    assert not marker.exists()


@pytest.mark.parametrize(
    "target",
    [
        "os.system",
        "builtins.exec",
        "subprocess.Popen",
        "prg.models.muse.os.system",  # a path through a project module
        "prg.models.checkpoint.read_checkpoint",  # the project's, but a function
        "torch.optim.lr_scheduler.LambdaLR.__init__",
        "torch.save",
        "torch.nn.Linear",  # a module, but not one of the project's models
        "prg.models.muse.MUSEE",
    ],
)
def test_a_checkpoint_naming_anything_but_our_models_and_torch_optimizers_is_refused(
    tmp_path, target
):
    ckpt = tmp_path / "odd.ckpt"
    _checkpoint_naming(ckpt, target)
    with pytest.raises(UsageError, match=rf"refused: it asks to build '{target}'"):
        read_checkpoint(ckpt)


def test_our_own_targets_are_accepted():
    check_targets(
        {
            "model": {"_target_": "prg.models.muse.MUSE"},
            "optimizer": {"_target_": "torch.optim.Adam", "_partial_": True},
            "scheduler": {"_target_": "torch.optim.lr_scheduler.OneCycleLR", "_partial_": True},
            "nested": [{"_target_": "prg.models.cvae.CVAE"}],
        },
        "x.ckpt",
    )


def test_coherence_cells_follow_what_each_family_accepts(trained_root):
    for family in FAMILIES:
        model, _ = load_model(trained_root / f"models/{family}/model.ckpt")
        cells = coherence_cells(model)
        assert {given for _, given in cells} == set(model.accepted_inputs)
        assert {target for target, _ in cells} == set(model.generated_modalities)
