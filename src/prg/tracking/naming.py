"""What MLflow shows of a run: the experiment kind and description tags, the sweep parent's
environment variable, metric names by the paper's letters, flattened params, the command line a
run was made with, and the UI's address of an experiment's runs."""

from __future__ import annotations

import functools
import re
import shlex
from collections.abc import Mapping
from typing import Any

PARENT_ENV = "PRG_PARENT_RUN_ID"
EXPERIMENT_KIND = {"mlflow.experimentKind": "custom_model_development"}
"""The experiment tag the MLflow UI writes when a user picks "Machine learning" as an
experiment's kind (``mlflow/server/js``: ``ExperimentKind.CUSTOM_MODEL_DEVELOPMENT``)."""
DESCRIPTION_TAG = "mlflow.note.content"  # the run's description in the MLflow UI


@functools.cache
def _modality_names() -> tuple[re.Pattern, Mapping[str, str]]:
    from prg.models.modalities import LETTER  # imports torch: only when metrics are logged

    return re.compile(r"(?<![A-Za-z0-9])(" + "|".join(LETTER) + r")(?![A-Za-z0-9])"), LETTER


def metric_name(key: str) -> str:
    """``key`` with each modality name as the paper's letter (``val/kl_label`` ->
    ``val/kl_S``, ``classifier/traj/test_accuracy`` -> ``classifier/T/test_accuracy``)."""
    pattern, letter = _modality_names()
    return pattern.sub(lambda m: letter[m.group(1)], key)


def runs_page(experiment_id: str, ui: str = "http://127.0.0.1:5000") -> str:
    """The MLflow UI's runs table of an experiment, in the "Model training" view."""
    return f"{ui}/#/experiments/{experiment_id}/runs?workflowType=machine_learning"


def command_line(command: str) -> str:
    """``command`` with the Hydra overrides of the running job (as typed, shell-quoted); inside
    a multirun, the job's own overrides (the command that reruns this job alone)."""
    from hydra.core.hydra_config import HydraConfig

    if not HydraConfig.initialized():
        return f"{command} (called from Python)"
    return " ".join([command, *map(shlex.quote, HydraConfig.get().overrides.task)])


def flatten(cfg: Any, prefix: str = "") -> dict[str, Any]:
    """Nested dict/list config -> ``{"a.b.c": value}`` with scalar values (MLflow params)."""
    out: dict[str, Any] = {}
    if isinstance(cfg, dict):
        for key, value in cfg.items():
            out.update(flatten(value, f"{prefix}{key}."))
    elif isinstance(cfg, list | tuple) and any(isinstance(v, dict | list) for v in cfg):
        for i, value in enumerate(cfg):
            out.update(flatten(value, f"{prefix}{i}."))
    else:
        out[prefix[:-1]] = cfg
    return out
