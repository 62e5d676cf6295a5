"""A checkpoint is data: opening one never runs code, and it may only name the project's models
and torch's optimizers and schedulers to build."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
import torch

from prg.errors import UsageError
from prg.models.checkpoint import check_targets, load_model, read_checkpoint


class _RunsCode:
    """Unpickling this calls ``os.system``: what a hostile checkpoint would do."""

    def __init__(self, command: str):
        self.command = command

    def __reduce__(self):
        return (os.system, (self.command,))


def _hostile_pickle(path, marker) -> None:
    torch.save(
        {"state_dict": {}, "hyper_parameters": {}, "payload": _RunsCode(f"touch {marker}")}, path
    )


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


def test_prg_write_refuses_a_hostile_checkpoint_in_one_line_and_creates_nothing(tmp_path):
    marker = tmp_path / "pwned"
    ckpt = tmp_path / "evil.ckpt"
    _hostile_pickle(ckpt, marker)
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "prg.commands.write",
            "text=cat",
            f"ckpt={ckpt}",
            f"out_dir={tmp_path}/o",
        ],
        cwd=tmp_path,
        env={**os.environ, "PRG_ROOT": str(tmp_path)},  # logs there, not in the checkout
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 2, result.stderr
    lines = [x for x in result.stderr.splitlines() if x.strip()]
    assert len(lines) == 1 and "refused" in lines[0] and str(ckpt) in lines[0], result.stderr
    assert not marker.exists() and not (tmp_path / "o").exists()
