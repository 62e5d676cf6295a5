"""Which MLflow store, and opening it: the tracking URI (``MLFLOW_TRACKING_URI``, else the
configured one, else the project's SQLite ``mlruns.db``), absolute ``file://`` artifact locations,
a client that creates a new SQLite store's tables one process at a time, and the experiments
(created with their kind tag, tolerating a concurrent creation)."""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path
from typing import Any

from prg.tracking.naming import EXPERIMENT_KIND


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
    """Id of the experiment ``name``, created (with its artifact location and
    :data:`EXPERIMENT_KIND`) if missing; an existing one without a kind gets the tag.

    On a tracking server the location is the server's (``artifacts`` is ignored). Tolerates a
    concurrent creation by another sweep job.
    """
    from mlflow.exceptions import MlflowException

    if is_server(client.tracking_uri):
        artifacts = None
    for _ in range(5):
        experiment = client.get_experiment_by_name(name)
        if experiment is not None:
            for key, value in EXPERIMENT_KIND.items():
                if key not in experiment.tags:  # a kind picked in the UI stays
                    client.set_experiment_tag(experiment.experiment_id, key, value)
            return experiment.experiment_id
        try:
            return client.create_experiment(name, artifact_location=artifacts, tags=EXPERIMENT_KIND)
        except MlflowException:
            time.sleep(0.5)
    raise RuntimeError(f"could not create or find MLflow experiment {name!r}")


def experiment_of(client, cfg: Any, tasks: bool) -> str:
    """Id of the configured experiment (``cfg.logger``) of training runs, or with ``tasks`` of
    the other commands' runs (``logger.task_experiment_name``)."""
    logger = cfg.logger
    name = logger.task_experiment_name if tasks else logger.experiment_name
    return get_experiment_id(client, name, artifact_location(logger.artifact_location))


def task_client(cfg: Any) -> tuple[Any, str]:
    """An ``MlflowClient`` on the configured store and the id of the task experiment
    (``cfg.logger``, ``cfg.paths.root_dir``), for commands that log runs themselves."""
    client = mlflow_client(tracking_uri(cfg.logger.get("tracking_uri"), cfg.paths.root_dir))
    return client, experiment_of(client, cfg, tasks=True)
