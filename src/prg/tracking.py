"""MLflow helpers: the default SQLite store, the logger, run tags, sweep parent runs.

Default store: ``sqlite:///<root>/mlruns.db`` with artifacts in ``<root>/mlartifacts``;
``MLFLOW_TRACKING_URI`` overrides the store (any server). Review runs with
``mlflow ui --backend-store-uri sqlite:///mlruns.db``.

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

import math
import os
import tempfile
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from hydra.experimental.callback import Callback as HydraCallback
from omegaconf import DictConfig

PARENT_ENV = "PRG_PARENT_RUN_ID"


def artifact_location(path: str | os.PathLike) -> str:
    """An absolute ``file://`` URI, so artifacts are found from any working directory."""
    return Path(path).expanduser().resolve().as_uri()


SQLITE_TIMEOUT_S = 60


def sqlite_uri(path: str | os.PathLike) -> str:
    """``sqlite:///`` URI of a database file (absolute, so any working directory works) that
    waits up to :data:`SQLITE_TIMEOUT_S` for another process's lock (pysqlite ``timeout``)."""
    return f"sqlite:///{Path(path).expanduser().resolve()}?timeout={SQLITE_TIMEOUT_S}"


def is_server(uri: str) -> bool:
    """Whether ``uri`` is a tracking server (which stores artifacts itself)."""
    return uri.startswith(("http://", "https://"))


def tracking_uri(configured: str | None, root_dir: str | os.PathLike) -> str:
    """``MLFLOW_TRACKING_URI`` if set, else the configured URI, else the project's SQLite."""
    return (
        os.environ.get("MLFLOW_TRACKING_URI")
        or configured
        or sqlite_uri(Path(root_dir) / "mlruns.db")
    )


_READY: set[str] = set()


def mlflow_client(uri: str):
    """An ``MlflowClient`` on ``uri``; a SQLite store's tables are created under a file lock.

    MLflow creates a new store's schema on first contact; processes doing that at the same time
    on one new file fail (``duplicate column name``), so they open stores in turns, the first
    time in each process.
    """
    from mlflow import MlflowClient

    if not uri.startswith("sqlite:") or uri in _READY:
        return MlflowClient(uri)
    import fcntl

    # one lock for all stores (opening one is quick); per user, as /tmp files are not shared
    with open(Path(tempfile.gettempdir()) / f"prg-mlflow-{os.getuid()}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        client = MlflowClient(uri)
        client.search_experiments(max_results=1)  # the store (and its tables) exist now
    _READY.add(uri)
    return client


def get_experiment_id(client, name: str, artifacts: str | None) -> str:
    """Id of the experiment ``name``, created (with its artifact location) if missing.

    On a tracking server the location is the server's (``artifacts`` is ignored). Tolerates a
    concurrent creation by another sweep job.
    """
    from mlflow.exceptions import MlflowException

    if is_server(client.tracking_uri):
        artifacts = None
    for _ in range(5):
        experiment = client.get_experiment_by_name(name)
        if experiment is not None:
            return experiment.experiment_id
        try:
            return client.create_experiment(name, artifact_location=artifacts)
        except MlflowException:
            time.sleep(0.5)
    raise RuntimeError(f"could not create or find MLflow experiment {name!r}")


def task_client(cfg: Any) -> tuple[Any, str]:
    """An ``MlflowClient`` on the configured store and the id of the configured experiment
    (``cfg.logger``, ``cfg.paths.root_dir``), for commands that log runs themselves."""
    client = mlflow_client(tracking_uri(cfg.logger.get("tracking_uri"), cfg.paths.root_dir))
    experiment = get_experiment_id(
        client, cfg.logger.experiment_name, artifact_location(cfg.logger.artifact_location)
    )
    return client, experiment


class TaskRun:
    """An open MLflow run of a command (:func:`task_run`): log params, metrics, text, artifacts."""

    PARAM_CHARS = 500  # MLflow's limit on a param value in older stores

    def __init__(self, client: Any, run_id: str):
        self.client = client
        self.run_id = run_id

    def log_params(self, params: Mapping[str, Any]) -> None:
        """``params`` (nested mappings flattened to ``a.b.c``), each value as text."""
        for key, value in flatten(dict(params)).items():
            self.client.log_param(self.run_id, key, str(value)[: self.PARAM_CHARS])

    def log_metrics(self, metrics: Mapping[str, Any], prefix: str = "") -> None:
        """The finite numbers of ``metrics``, each under ``prefix + key``; others are skipped."""
        now = int(time.time() * 1000)
        for key, value in metrics.items():
            if isinstance(value, bool) or not isinstance(value, int | float):
                continue
            if math.isfinite(value):
                self.client.log_metric(self.run_id, f"{prefix}{key}", float(value), timestamp=now)

    def log_text(self, text: str, name: str) -> None:
        self.client.log_text(self.run_id, text, name)

    def log_artifacts(self, folder: str | os.PathLike, path: str) -> None:
        self.client.log_artifacts(self.run_id, str(folder), path)


@contextmanager
def task_run(
    cfg: Any, task: str, tags: Mapping[str, str] | None = None, enabled: bool = True
) -> Iterator[TaskRun | None]:
    """The MLflow run of one command's work, on the configured store (``cfg.logger``,
    ``cfg.paths.root_dir``), named ``cfg.run_name`` and tagged ``prg.task=<task>`` (and the sweep's
    parent run inside a Hydra multirun).

    Opened before the work and ended after it: ``FINISHED`` when the block completes, ``FAILED``
    when it raises, ``KILLED`` when a signal stops it (the error is re-raised either way). With
    ``enabled=False`` nothing is opened and the block gets ``None``.
    """
    if not enabled:
        yield None
        return
    from prg.signals import Interrupted

    client, experiment = task_client(cfg)
    all_tags = {"prg.task": task, **(tags or {})}
    if os.environ.get(PARENT_ENV):
        all_tags["mlflow.parentRunId"] = os.environ[PARENT_ENV]
    run_id = client.create_run(experiment, run_name=cfg.run_name, tags=all_tags).info.run_id
    try:
        yield TaskRun(client, run_id)
    except (Interrupted, KeyboardInterrupt):
        client.set_terminated(run_id, status="KILLED")
        raise
    except BaseException:
        client.set_terminated(run_id, status="FAILED")
        raise
    client.set_terminated(run_id)


def mlflow_logger(
    experiment_name: str,
    run_name: str,
    tracking_uri: str,
    artifact_location: str,
    run_id: str | None = None,
    tags: dict[str, str] | None = None,
):
    """A Lightning ``MLFlowLogger`` on an explicit store (never the default ./mlruns)."""
    from lightning.pytorch.loggers import MLFlowLogger

    get_experiment_id(mlflow_client(tracking_uri), experiment_name, artifact_location)
    return MLFlowLogger(
        experiment_name=experiment_name,
        run_name=None if run_id else run_name,
        tracking_uri=tracking_uri,
        artifact_location=None if is_server(tracking_uri) else artifact_location,
        run_id=run_id,
        tags=None if run_id else tags,
        log_model=False,
    )


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


class SweepParentRun(HydraCallback):
    """Hydra callback: one MLflow parent run per multirun; jobs attach to it as children."""

    def __init__(self, enabled: bool = True):
        self.enabled = enabled
        self.run_id: str | None = None
        self.client = None

    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        if not self.enabled or "logger" not in config or os.environ.get(PARENT_ENV):
            return
        uri = tracking_uri(config.logger.get("tracking_uri"), config.paths.root_dir)
        self.client = mlflow_client(uri)
        experiment_id = get_experiment_id(
            self.client,
            config.logger.experiment_name,
            artifact_location(config.logger.artifact_location),
        )
        overrides = " ".join(config.hydra.overrides.task)
        run = self.client.create_run(
            experiment_id,
            run_name=f"sweep {time.strftime('%Y-%m-%d %H:%M:%S')}",
            tags={"prg.sweep": "parent", "prg.sweep.overrides": overrides[:5000]},
        )
        self.run_id = run.info.run_id
        os.environ[PARENT_ENV] = self.run_id

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        if self.run_id is not None:
            self.client.set_terminated(self.run_id)
            os.environ.pop(PARENT_ENV, None)
            self.run_id = None
