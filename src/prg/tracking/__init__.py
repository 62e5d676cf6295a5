"""MLflow helpers: the default SQLite store, the logger, run tags and descriptions, sweep parent
runs, moving a store.

One concept a module: :mod:`~prg.tracking.store` (which store, the client, experiments),
:mod:`~prg.tracking.naming` (tags, metric names, params, command lines, UI addresses),
:mod:`~prg.tracking.task_runs` (one run per command's work), :mod:`~prg.tracking.pending` (runs
logged by a background process), :mod:`~prg.tracking.lightning_logger` (the training logger),
:mod:`~prg.tracking.sweep` (a multirun's parent run) and :mod:`~prg.tracking.relocation`
(moving a store). Its command line (``python -m prg.tracking``) is :mod:`prg.commands.tracking`.

Default store: ``sqlite:///<root>/mlruns.db`` with artifacts in ``<root>/mlartifacts``;
``MLFLOW_TRACKING_URI`` overrides the store (any server). Review runs with
``mlflow ui --backend-store-uri sqlite:///mlruns.db``.

Training runs go to the experiment ``logger.experiment_name`` (``prg``), the runs of the other
commands (``prg-evaluate``, ``prg-write``, ``prg-simulate``, ``prg-dictaphone``) to
``logger.task_experiment_name`` (``prg-tasks``). Both are tagged ``mlflow.experimentKind =
custom_model_development`` (:data:`EXPERIMENT_KIND`), the kind the MLflow UI shows as "Machine
learning". MLflow 3.17's UI decides what an experiment opens on from its "GenAI / Model
training" switch (remembered per browser, or ``?workflowType=machine_learning`` in the address,
:func:`runs_page`), not from that tag; the tag still names the kind for the UI builds and tools
that read it.

Metric names sent to MLflow name modalities by the paper's letters, as the evaluation's metrics
and the report tables do (:func:`metric_name`: ``train/rec_traj`` -> ``train/rec_T``); the
trainer's own metrics and the DVC ``metrics.json`` files keep the modality names.

Artifact locations are absolute ``file://`` URIs (MLflow resolves a relative one against the
working folder when it creates an experiment, and ``mlflow-artifacts:`` URIs need a tracking
server), so a moved store is re-pointed with :func:`move_store`.

Several processes may write to one SQLite store at once (parallel sweep jobs): the default URI
waits up to 60 s for a lock (``?timeout=60``; MLflow's own sessions wait 20 s), and a new
store's tables are created by one process at a time (:func:`mlflow_client`). On a tracking
server (``http(s)://``) the server decides where artifacts go: experiments are created without
a local ``file://`` artifact location, and artifacts are uploaded through the server.

A Hydra multirun groups its jobs under one parent run: :class:`SweepParentRun` (a Hydra
callback, enabled in ``conf/hydra/default.yaml``) opens the parent when the sweep starts and
exports its id in ``PRG_PARENT_RUN_ID``; each job's run is tagged ``mlflow.parentRunId``.
"""

from __future__ import annotations

from typing import Any

from prg.tracking.lightning_logger import mlflow_logger
from prg.tracking.naming import (
    DESCRIPTION_TAG,
    EXPERIMENT_KIND,
    PARENT_ENV,
    command_line,
    flatten,
    metric_name,
    runs_page,
)
from prg.tracking.pending import PENDING_FOLDER, hand_off_run, log_pending_run
from prg.tracking.relocation import move_store
from prg.tracking.store import (
    SQLITE_TIMEOUT_S,
    artifact_location,
    experiment_of,
    get_experiment_id,
    is_server,
    mlflow_client,
    sqlite_uri,
    task_client,
    tracking_uri,
)
from prg.tracking.sweep import SweepParentRun
from prg.tracking.task_runs import (
    PARAM_CHARS,
    TASKS,
    PendingRun,
    TaskRun,
    task_description,
    task_run,
)

__all__ = [
    "DESCRIPTION_TAG",
    "EXPERIMENT_KIND",
    "PARAM_CHARS",
    "PARENT_ENV",
    "PENDING_FOLDER",
    "SQLITE_TIMEOUT_S",
    "TASKS",
    "USAGE",
    "PendingRun",
    "SweepParentRun",
    "TaskRun",
    "artifact_location",
    "command_line",
    "experiment_of",
    "flatten",
    "get_experiment_id",
    "hand_off_run",
    "is_server",
    "log_pending_run",
    "main",
    "metric_name",
    "mlflow_client",
    "mlflow_logger",
    "move_store",
    "runs_page",
    "sqlite_uri",
    "task_client",
    "task_description",
    "task_run",
    "tracking_uri",
]

_COMMAND_LINE = {"main", "USAGE"}  # kept here for existing callers: prg.commands.tracking's


def __getattr__(name: str) -> Any:
    """``main`` and ``USAGE``, the command line's (:mod:`prg.commands.tracking`), loaded by name
    on first use so that importing this library never loads the command layer."""
    if name in _COMMAND_LINE:
        import importlib

        return getattr(importlib.import_module("prg.commands.tracking"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
