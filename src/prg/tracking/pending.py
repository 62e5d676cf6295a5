"""Runs handed to the background: a command's run written as a JSON file under
``<paths.log_dir>/pending-runs/`` (:func:`hand_off_run`) and logged to its store by a detached
``python -m prg.tracking log-pending FILE`` (:func:`log_pending_run`), so a short command does
not wait for MLflow (:func:`prg.tracking.task_run` with ``background=True``)."""

from __future__ import annotations

import os
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from prg.errors import UsageError
from prg.tracking.store import get_experiment_id, mlflow_client

PENDING_FOLDER = "pending-runs"  # under paths.log_dir: runs handed to a background process


def hand_off_run(spec: Mapping[str, Any], folder: Path, task: str) -> Path:
    """Write a pending run's ``spec`` (:func:`~prg.tracking.task_run`) into ``folder`` atomically
    and start a detached process that logs it (:func:`log_pending_run`; its own session, so a
    signal to the command's process group does not stop it); returns the spec's path."""
    import json
    import subprocess
    import sys

    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{task}-{time.strftime('%Y%m%d-%H%M%S')}-{os.getpid()}.json"
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(json.dumps(spec), encoding="utf-8")
    tmp.replace(path)
    with open(folder / "log.txt", "a", encoding="utf-8") as log:
        subprocess.Popen(
            [sys.executable, "-m", "prg.tracking", "log-pending", str(path)],
            stdin=subprocess.DEVNULL,
            stdout=log,
            stderr=log,
            start_new_session=True,
        )
    return path


def log_pending_run(path: str | os.PathLike) -> str:
    """Log the pending run that :func:`hand_off_run` wrote at ``path`` (tags, params and metrics
    in one batch, texts, artifacts, its status and times), then delete the file; returns the run
    id. A file that is not such a run is a :class:`~prg.errors.UsageError`; when logging fails
    the partly logged run is deleted and the file kept, so it can be logged again."""
    import json

    from mlflow.entities import Metric, Param

    path = Path(path)
    try:
        spec = json.loads(path.read_text(encoding="utf-8"))
        uri, experiment_name = spec["tracking_uri"], spec["experiment"]
        location, start_ms, end_ms = spec["artifact_location"], spec["start_ms"], spec["end_ms"]
        run_name, tags, status = spec["run_name"], spec["tags"], spec["status"]
        params, metrics = dict(spec["params"]), dict(spec["metrics"])
        texts, artifacts = dict(spec["texts"]), [tuple(a) for a in spec["artifacts"]]
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise UsageError(f"pending run {path}: not a pending run file ({err})") from None
    missing = [folder for folder, _ in artifacts if not Path(folder).is_dir()]
    if missing:  # MLflow would log an empty folder without a word
        raise FileNotFoundError(f"the run's output folder {missing[0]} is gone")
    client = mlflow_client(uri)
    experiment = get_experiment_id(client, experiment_name, location)
    run_id = client.create_run(
        experiment, start_time=start_ms, run_name=run_name, tags=tags
    ).info.run_id
    try:
        client.log_batch(
            run_id,
            metrics=[Metric(key, value, end_ms, 0) for key, value in metrics.items()],
            params=[Param(key, value) for key, value in params.items()],
        )
        for name, text in texts.items():
            client.log_text(run_id, text, name)
        for folder, artifact_path in artifacts:
            client.log_artifacts(run_id, folder, artifact_path)
        client.set_terminated(run_id, status=status, end_time=end_ms)
    except BaseException:
        client.delete_run(run_id)  # no half-logged run; the kept file logs it whole next time
        raise
    path.unlink()
    return run_id
