"""One MLflow run per command's work (:func:`task_run`): opened on the configured store before
the work, ended with the work's status, in the task experiment with a description; logged
either at once (:class:`TaskRun`) or, kept as plain data (:class:`PendingRun`), by a background
process afterwards (:mod:`prg.tracking.pending`)."""

from __future__ import annotations

import math
import os
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from prg.tracking.naming import DESCRIPTION_TAG, PARENT_ENV, command_line, flatten
from prg.tracking.pending import PENDING_FOLDER, hand_off_run
from prg.tracking.store import artifact_location, task_client, tracking_uri

TASKS = {
    "evaluate": "Table I log-likelihoods, coherence and robustness of trained models",
    "write": "a word written by a trained model (prg-write)",
    "simulate": "a simulated arm writing a word (prg-simulate)",
    "dictaphone": "Table II: words written from speech and from letter images",
}


def task_description(task: str, tags: Mapping[str, str]) -> str:
    """The MLflow description of a command's run: what it does, with which model, the command."""
    lines = [f"**prg-{task}**: {TASKS.get(task, task)}"]
    if "prg.family" in tags:
        lines.append(f"Model: `{tags['prg.family']}`")
    if "prg.data.name" in tags:
        lines.append(f"Data: `{tags['prg.data.name']}`")
    lines.append(f"Command: `{command_line(f'prg-{task}')}`")
    return "  \n".join(lines)


def _param_texts(params: Mapping[str, Any]) -> dict[str, str]:
    """``params`` flattened to ``a.b.c``, each value as text of at most :data:`PARAM_CHARS`."""
    return {key: str(value)[:PARAM_CHARS] for key, value in flatten(dict(params)).items()}


def _finite_metrics(metrics: Mapping[str, Any], prefix: str) -> dict[str, float]:
    """The finite numbers of ``metrics`` under ``prefix + key``; other values are left out."""
    return {
        f"{prefix}{key}": float(value)
        for key, value in metrics.items()
        if not isinstance(value, bool) and isinstance(value, int | float) and math.isfinite(value)
    }


PARAM_CHARS = 500  # MLflow's limit on a param value in older stores


class TaskRun:
    """An open MLflow run of a command (:func:`task_run`): log tags, params, metrics, text,
    artifacts."""

    def __init__(self, client: Any, run_id: str):
        self.client = client
        self.run_id = run_id

    def set_tag(self, key: str, value: Any) -> None:
        self.client.set_tag(self.run_id, key, str(value))

    def log_params(self, params: Mapping[str, Any]) -> None:
        """``params`` (nested mappings flattened to ``a.b.c``), each value as text."""
        for key, value in _param_texts(params).items():
            self.client.log_param(self.run_id, key, value)

    def log_metrics(self, metrics: Mapping[str, Any], prefix: str = "") -> None:
        """The finite numbers of ``metrics``, each under ``prefix + key``; others are skipped."""
        now = int(time.time() * 1000)
        for key, value in _finite_metrics(metrics, prefix).items():
            self.client.log_metric(self.run_id, key, value, timestamp=now)

    def log_text(self, text: str, name: str) -> None:
        self.client.log_text(self.run_id, text, name)

    def log_artifacts(self, folder: str | os.PathLike, path: str) -> None:
        self.client.log_artifacts(self.run_id, str(folder), path)


class PendingRun:
    """What a :class:`TaskRun` would log (the same methods), kept as plain data for
    :func:`~prg.tracking.pending.log_pending_run` to log later in another process
    (:func:`task_run` with ``background=True``)."""

    def __init__(self) -> None:
        self.tags: dict[str, str] = {}
        self.params: dict[str, str] = {}
        self.metrics: dict[str, float] = {}
        self.texts: dict[str, str] = {}
        self.artifacts: list[tuple[str, str]] = []  # (absolute folder, artifact path)

    def set_tag(self, key: str, value: Any) -> None:
        self.tags[key] = str(value)

    def log_params(self, params: Mapping[str, Any]) -> None:
        self.params.update(_param_texts(params))

    def log_metrics(self, metrics: Mapping[str, Any], prefix: str = "") -> None:
        self.metrics.update(_finite_metrics(metrics, prefix))

    def log_text(self, text: str, name: str) -> None:
        self.texts[name] = text

    def log_artifacts(self, folder: str | os.PathLike, path: str) -> None:
        self.artifacts.append((str(Path(folder).resolve()), path))


@contextmanager
def task_run(
    cfg: Any,
    task: str,
    tags: Mapping[str, str] | None = None,
    enabled: bool = True,
    background: bool = False,
) -> Iterator[TaskRun | PendingRun | None]:
    """The MLflow run of one command's work, on the configured store (``cfg.logger``,
    ``cfg.paths.root_dir``), named ``cfg.run_name`` and tagged ``prg.task=<task>`` (and the sweep's
    parent run inside a Hydra multirun), in the task experiment (``logger.task_experiment_name``)
    with a description (:func:`task_description`).

    Opened before the work and ended after it: ``FINISHED`` when the block completes, ``FAILED``
    when it raises, ``KILLED`` when a signal stops it (the error is re-raised either way). With
    ``enabled=False`` nothing is opened and the block gets ``None``.

    With ``background=True`` the block gets a :class:`PendingRun` and MLflow is not imported
    here (importing it and opening a store cost a short command most of its time): when the
    block ends, the run, with its real start and end times and status, is written to
    ``<paths.log_dir>/pending-runs/`` and logged by a detached process
    (``python -m prg.tracking log-pending FILE``), which deletes the file once the run is in the
    store; after a failure the file stays, with the error in ``pending-runs/log.txt``.
    """
    if not enabled:
        yield None
        return
    from prg.signals import Interrupted

    all_tags = {"prg.task": task, **(tags or {})}
    all_tags[DESCRIPTION_TAG] = task_description(task, all_tags)
    if os.environ.get(PARENT_ENV):
        all_tags["mlflow.parentRunId"] = os.environ[PARENT_ENV]
    if background:
        pending, start_ms, status = PendingRun(), int(time.time() * 1000), "FINISHED"
        try:
            yield pending
        except (Interrupted, KeyboardInterrupt):
            status = "KILLED"
            raise
        except BaseException:
            status = "FAILED"
            raise
        finally:
            spec = {
                "tracking_uri": tracking_uri(cfg.logger.get("tracking_uri"), cfg.paths.root_dir),
                "experiment": cfg.logger.task_experiment_name,
                "artifact_location": artifact_location(cfg.logger.artifact_location),
                "run_name": cfg.run_name,
                "tags": {**all_tags, **pending.tags},
                "params": pending.params,
                "metrics": pending.metrics,
                "texts": pending.texts,
                "artifacts": pending.artifacts,
                "status": status,
                "start_ms": start_ms,
                "end_ms": int(time.time() * 1000),
            }
            hand_off_run(spec, Path(cfg.paths.log_dir) / PENDING_FOLDER, task)
        return
    client, experiment = task_client(cfg)
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
