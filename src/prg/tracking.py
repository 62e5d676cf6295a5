"""MLflow helpers: the default SQLite store, the logger, run tags and descriptions, sweep parent
runs, moving a store.

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

import functools
import math
import os
import re
import shlex
import sqlite3
import tempfile
import time
from collections.abc import Iterator, Mapping
from contextlib import closing, contextmanager
from pathlib import Path
from typing import Any

from hydra.experimental.callback import Callback as HydraCallback
from omegaconf import DictConfig

from prg.errors import UsageError

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
    :func:`log_pending_run` to log later in another process (:func:`task_run` with
    ``background=True``)."""

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


PENDING_FOLDER = "pending-runs"  # under paths.log_dir: runs handed to a background process


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


def hand_off_run(spec: Mapping[str, Any], folder: Path, task: str) -> Path:
    """Write a pending run's ``spec`` (:func:`task_run`) into ``folder`` atomically and start a
    detached process that logs it (:func:`log_pending_run`; its own session, so a signal to the
    command's process group does not stop it); returns the spec's path."""
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


def mlflow_logger(
    experiment_name: str,
    run_name: str,
    tracking_uri: str,
    artifact_location: str,
    run_id: str | None = None,
    tags: dict[str, str] | None = None,
    task_experiment_name: str | None = None,
):
    """A Lightning MLflow logger on an explicit store (never the default ./mlruns), logging to
    the training experiment (``task_experiment_name`` is the other commands') with the project's
    metric names (:class:`prg.training.mlflow_logger.LetterNamedMLFlowLogger`)."""
    from prg.training.mlflow_logger import LetterNamedMLFlowLogger

    get_experiment_id(mlflow_client(tracking_uri), experiment_name, artifact_location)
    return LetterNamedMLFlowLogger(
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
        # a sweep of prg-train groups training runs; of another command, that command's runs
        experiment_id = experiment_of(self.client, config, tasks="trainer" not in config)
        overrides = " ".join(config.hydra.overrides.task)
        command = f"prg-{config.hydra.job.config_name} -m {overrides}"
        run = self.client.create_run(
            experiment_id,
            run_name=f"sweep {time.strftime('%Y-%m-%d %H:%M:%S')}",
            tags={
                "prg.sweep": "parent",
                "prg.sweep.overrides": overrides[:5000],
                DESCRIPTION_TAG: f"A sweep: its jobs are the child runs.  \nCommand: `{command}`",
            },
        )
        self.run_id = run.info.run_id
        os.environ[PARENT_ENV] = self.run_id

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        if self.run_id is not None:
            self.client.set_terminated(self.run_id)
            os.environ.pop(PARENT_ENV, None)
            self.run_id = None


# Where an MLflow SQLite store records artifact locations (tables and columns of MLflow 3).
_LOCATIONS = {
    "experiments": ("artifact_location",),
    "runs": ("artifact_uri",),
    "model_versions": ("source", "storage_location"),
    "logged_models": ("artifact_location",),
}


def move_store(
    db: str | os.PathLike, old_artifacts: str | os.PathLike, new_artifacts: str | os.PathLike
) -> int:
    """Re-point a moved SQLite store: every artifact location under ``old_artifacts`` (the
    artifacts folder before the move, as a path) now under ``new_artifacts`` (where it is now).
    Experiments created afterwards get the location that ``logger.artifact_location`` gives.
    Returns how many locations changed; a bad input is a :class:`~prg.errors.UsageError`."""
    db, new = Path(db), Path(new_artifacts).expanduser().resolve()
    old = Path(os.path.abspath(Path(old_artifacts).expanduser()))  # it need not exist any more
    if not db.is_file():
        raise UsageError(f"store {db}: no such file (the mlruns.db to re-point)")
    if not new.is_dir():
        raise UsageError(f"new artifacts folder {new}: no such folder (move mlartifacts first)")
    changed = 0
    with closing(sqlite3.connect(db, timeout=SQLITE_TIMEOUT_S)) as con, con:
        tables = {r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type='table'")}
        if not {"experiments", "runs"} <= tables:
            raise UsageError(f"store {db}: not an MLflow SQLite store (no experiments/runs tables)")
        for table, columns in _LOCATIONS.items():
            present = {r[1] for r in con.execute(f"PRAGMA table_info({table})")}
            for column in (c for c in columns if c in present):
                for before, after in ((old.as_uri(), new.as_uri()), (str(old), str(new))):
                    changed += con.execute(
                        f"UPDATE {table} SET {column} = ? || substr({column}, ?) "
                        f"WHERE substr({column}, 1, ?) = ? "
                        f"AND substr({column}, ?, 1) IN ('', '/')",
                        (after, len(before) + 1, len(before), before, len(before) + 1),
                    ).rowcount
    return changed


USAGE = (
    "python -m prg.tracking move-store DB OLD_ARTIFACTS NEW_ARTIFACTS"
    " | python -m prg.tracking log-pending FILE"
)


def main(argv: list[str]) -> int:
    """``python -m prg.tracking move-store mlruns.db /old/checkout/mlartifacts mlartifacts``, or
    ``python -m prg.tracking log-pending logs/pending-runs/write-....json``: log a run that a
    command handed to the background (:func:`task_run`), again after a failure."""
    import sys

    moving = argv[:1] == ["move-store"] and len(argv) == 4
    if not moving and not (argv[:1] == ["log-pending"] and len(argv) == 2):
        print(f"prg.tracking: error: usage: {USAGE}", file=sys.stderr)
        return 2
    try:
        if not moving:
            os.nice(10)  # behind the commands the user is waiting for
            stamp = time.strftime("%Y-%m-%d %H:%M:%S")
            try:
                run_id = log_pending_run(argv[1])
            except UsageError:
                raise
            except Exception as err:  # the store or an artifact: the file is kept for a retry
                print(
                    f"prg.tracking: error: {stamp} pending run {argv[1]} not logged"
                    f" ({type(err).__name__}: {err}); the file is kept: run"
                    f" `python -m prg.tracking log-pending {argv[1]}` again",
                    file=sys.stderr,
                )
                return 1
            print(f"{stamp} logged run {run_id} from {argv[1]}")
            return 0
        changed = move_store(*argv[1:])
    except UsageError as err:
        print(f"prg.tracking: error: {err}", file=sys.stderr)
        return 2
    print(f"{changed} artifact locations now under {Path(argv[3]).resolve()}")
    return 0


if __name__ == "__main__":
    import sys

    sys.exit(main(sys.argv[1:]))
