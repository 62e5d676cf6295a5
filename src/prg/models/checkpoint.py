"""Reading training checkpoints: the raw dict (for resuming) or the model ready to use.

A checkpoint is data, never code: it is unpickled with ``torch.load(weights_only=True)`` (tensors,
numbers, strings and containers only: what our checkpoints hold), and the classes its
hyper-parameters ask to instantiate (``_target_``) must be the project's models or PyTorch's
optimizers and learning-rate schedulers. Anything else is refused with one line before any of it
is built."""

from __future__ import annotations

import importlib
import os
import pickle
import re
from pathlib import Path
from typing import Any

import torch

from prg.data.hands import CHECKPOINT_KEY as HANDS_KEY
from prg.data.hands import HandBank
from prg.errors import UsageError
from prg.files import read_json
from prg.models.base import MultimodalVAE

#: Entries of a training checkpoint that describe the run, not the model: the MLflow run and
#: store, the callbacks' state (the checkpoint folder's paths) and the job identity that resuming
#: matches (it hashes the resolved config, paths included). An exported ``model.ckpt`` leaves
#: them out (:func:`without_run_facts`), so the same training gives the same file wherever it
#: ran and whatever run logged it; its run id is in the ``metrics.json`` beside it.
RUN_FACTS = (
    "mlflow_run_id",
    "mlflow_tracking_uri",
    "callbacks",
    "prg_job",
    "prg_random_state",  # where this run goes on (LastCheckpoint), not the model
    "prg_training_order",
)


def without_run_facts(ckpt: dict[str, Any]) -> dict[str, Any]:
    """``ckpt`` without :data:`RUN_FACTS` (a shallow copy)."""
    return {k: v for k, v in ckpt.items() if k not in RUN_FACTS}


def read_checkpoint(path: str | os.PathLike) -> dict[str, Any]:
    """Load a Lightning checkpoint's dict, or raise a UsageError naming the file."""
    path = Path(path)
    if path.is_dir():
        raise UsageError(f"checkpoint {path} is a folder; give the .ckpt file inside it")
    if not path.is_file():
        raise UsageError(f"checkpoint {path} does not exist")
    try:
        ckpt = torch.load(path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError as err:
        found = re.search(r"GLOBAL ([\w.]+)", str(err))  # the class or function it names
        if found is None:  # not a pickle of ours at all
            raise UsageError(
                f"checkpoint {path} is not a readable checkpoint (UnpicklingError)"
            ) from None
        raise UsageError(
            f"checkpoint {path} refused: it holds a {found.group(1)} object, not only tensors "
            "and plain data (loading it could run code)"
        ) from None
    except Exception as err:  # torch raises many types for a file that is not a checkpoint
        raise UsageError(
            f"checkpoint {path} is not a readable checkpoint ({type(err).__name__})"
        ) from None
    problem = _shape_problem(ckpt)
    if problem:
        raise UsageError(
            f"checkpoint {path} is not a prg training checkpoint ({problem}); accepted: a "
            "model.ckpt, best.ckpt or last.ckpt written by prg-train"
        )
    check_targets(ckpt["hyper_parameters"], path)
    return ckpt


def _shape_problem(ckpt: Any) -> str | None:
    """What a loaded checkpoint lacks of the entries every reader uses: a ``state_dict`` of
    tensors and ``hyper_parameters`` whose ``model`` names its class (``_target_``); None when
    it has them."""
    if not isinstance(ckpt, dict):
        return f"it holds a {type(ckpt).__name__}, not a dict"
    weights, hparams = ckpt.get("state_dict"), ckpt.get("hyper_parameters")
    if not isinstance(weights, dict) or not all(
        isinstance(k, str) and isinstance(v, torch.Tensor) for k, v in weights.items()
    ):
        return "no state_dict of named tensors"
    if not isinstance(hparams, dict):
        return "no hyper_parameters"
    model = hparams.get("model")
    if not isinstance(model, dict) or not isinstance(model.get("_target_"), str):
        return "its hyper_parameters have no model._target_"
    return None


# What a checkpoint's hyper-parameters may instantiate: (module prefix, required base class).
ALLOWED_TARGETS = (
    ("prg.models.", "torch.nn.Module"),
    ("torch.optim.lr_scheduler.", "torch.optim.lr_scheduler.LRScheduler"),
    ("torch.optim.", "torch.optim.Optimizer"),
)


def _resolve(dotted: str) -> Any:
    module, _, name = dotted.rpartition(".")
    return getattr(importlib.import_module(module), name)


def check_targets(hparams: Any, path: str | os.PathLike) -> None:
    """Raise a UsageError unless every ``_target_`` in ``hparams`` names one of the project's
    model classes or a PyTorch optimizer or scheduler class (:data:`ALLOWED_TARGETS`)."""
    stack = [hparams]
    while stack:
        node = stack.pop()
        if isinstance(node, dict):
            stack.extend(node.values())
            target = node.get("_target_")
            if target is not None and not _allowed(target):
                raise UsageError(
                    f"checkpoint {path} refused: it asks to build {target!r}; a checkpoint may "
                    f"name only prg's models and torch's optimizers and schedulers"
                )
        elif isinstance(node, (list, tuple)):
            stack.extend(node)


def _allowed(target: Any) -> bool:
    if not isinstance(target, str):
        return False
    for prefix, base in ALLOWED_TARGETS:
        if target.startswith(prefix):
            try:
                cls = _resolve(target)
            except (ImportError, AttributeError, ValueError):
                return False
            return isinstance(cls, type) and issubclass(cls, _resolve(base))
    return False


def _exported_run(path: Path) -> dict[str, str]:
    """``{"mlflow_run_id": ...}`` from the ``metrics.json`` that ``prg-train`` exports beside a
    ``model.ckpt``; empty when there is none or it names no run."""
    try:
        exported = read_json(path.parent / "metrics.json", "exported metrics")
    except UsageError:
        return {}
    run_id = exported.get("mlflow_run_id") if isinstance(exported, dict) else None
    return {"mlflow_run_id": run_id} if isinstance(run_id, str) and run_id else {}


def load_model(path: str | os.PathLike) -> tuple[MultimodalVAE, dict[str, Any]]:
    """The trained model of a checkpoint (eval mode, CPU) and the checkpoint's extra entries
    (``mlflow_run_id``, from the ``metrics.json`` beside an exported ``model.ckpt``; ``epoch``,
    ``global_step``; no weights), and ``hands``: the
    training writers' letters (:class:`~prg.data.hands.HandBank`) when the checkpoint has them.

    Built from the checkpoint's ``model`` hyper-parameters and the ``model.``-prefixed weights of
    :class:`~prg.models.module.PRGModule`'s state dict, without the LightningModule: importing
    Lightning costs a generating command more than the generation itself."""
    from hydra.utils import instantiate

    ckpt = read_checkpoint(path)
    prefix = "model."
    weights = {k[len(prefix) :]: v for k, v in ckpt["state_dict"].items() if k.startswith(prefix)}
    try:
        model = instantiate(ckpt["hyper_parameters"]["model"], _convert_="all")
        model.load_state_dict(weights)
    except Exception as err:  # wrong keys or shapes: written by another version of the code
        first = " ".join(str(err).split())[:200]
        raise UsageError(f"checkpoint {path} does not match this code's models: {first}") from None
    if hasattr(model, "kl_scale") and "kl_scale" in ckpt:
        model.kl_scale = ckpt["kl_scale"]
    info = {k: v for k, v in ckpt.items() if k in ("mlflow_run_id", "epoch", "global_step")}
    if "mlflow_run_id" not in info:  # an exported model.ckpt: the run is named beside it
        info.update(_exported_run(Path(path)))
    if HANDS_KEY in ckpt:
        try:
            info[HANDS_KEY] = HandBank.from_checkpoint(ckpt[HANDS_KEY])
        except (KeyError, TypeError, AttributeError, ValueError):
            raise UsageError(f"checkpoint {path}: its writers' letters are unreadable") from None
    return model.eval(), info
