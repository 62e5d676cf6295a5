"""Reading training checkpoints: the raw dict (for resuming) or the model ready to use."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import torch

from prg.errors import UsageError
from prg.models.base import MultimodalVAE


def read_checkpoint(path: str | os.PathLike) -> dict[str, Any]:
    """Load a Lightning checkpoint's dict, or raise a UsageError naming the file."""
    path = Path(path)
    if path.is_dir():
        raise UsageError(f"checkpoint {path} is a folder; give the .ckpt file inside it")
    if not path.is_file():
        raise UsageError(f"checkpoint {path} does not exist")
    try:
        ckpt = torch.load(path, map_location="cpu", weights_only=False)
    except Exception as err:  # torch raises many types for a file that is not a checkpoint
        raise UsageError(
            f"checkpoint {path} is not a readable checkpoint ({type(err).__name__})"
        ) from None
    if not isinstance(ckpt, dict) or "state_dict" not in ckpt or "hyper_parameters" not in ckpt:
        raise UsageError(f"checkpoint {path} is not a prg training checkpoint")
    return ckpt


def load_model(path: str | os.PathLike) -> tuple[MultimodalVAE, dict[str, Any]]:
    """The trained model of a checkpoint (eval mode, CPU) and the checkpoint's extra entries
    (``mlflow_run_id``, ``epoch``, ``global_step`` ... ; no weights)."""
    from prg.models.module import PRGModule

    ckpt = read_checkpoint(path)
    try:
        module = PRGModule(**ckpt["hyper_parameters"])
        module.load_state_dict(ckpt["state_dict"])
    except Exception as err:  # wrong keys or shapes: written by another version of the code
        first = " ".join(str(err).split())[:200]
        raise UsageError(f"checkpoint {path} does not match this code's models: {first}") from None
    module.on_load_checkpoint(ckpt)
    info = {k: v for k, v in ckpt.items() if k in ("mlflow_run_id", "epoch", "global_step")}
    return module.model.eval(), info
