"""``prg-train``: train one model family (Hydra; multirun sweeps group under an MLflow parent).

Examples
--------
``prg-train model=muse experiment=quick``
``prg-train -m model=cvae,avae_ts,avae_ti,muse seed=0,1 experiment=quick``
``prg-train model=muse ckpt_path=checkpoints/prg/muse-seed0/last.ckpt``   resume, same MLflow run
``prg-train model=muse ckpt_path=last``   the same: ``${checkpoint_dir}/last.ckpt`` of this run

Resuming after a crash or a kill: ``ckpt_path=last`` resolves to ``${checkpoint_dir}/last.ckpt``
(a one-line usage error, exit 2, when there is none). ``last.ckpt`` is refreshed every
``callbacks.last.every_n_train_steps`` steps inside an epoch, at the end of each epoch and at the
end of training (:class:`prg.training.callbacks.LastCheckpoint`), so a kill loses at most that many steps.
The resumed run finishes the interrupted epoch's remaining batches, continues the same MLflow
run (its id travels in the checkpoint) and marks it FINISHED at the end. The epoch means
``train/*`` and ``val/*`` are logged once per epoch, at the epoch's last step, so the run's
history has each epoch once (see ``LastCheckpoint`` for the one sub-second window where a kill
leaves an epoch's ``val/*`` twice); ``train_steps/*`` are the means over each
``trainer.log_every_n_steps`` steps (:class:`prg.training.callbacks.StepMeans`).

Sweeps that survive being stopped (``resume``, :func:`plan_job`): in a multirun (``-m``, any
launcher) each job first looks at its ``checkpoint_dir``. A job that finished before with the same
identity (family, seed, profile, data manifest hash and the hash of its resolved config, the
``resume`` and ``ckpt_path`` options left out: :func:`job_identity`), as recorded in
``finished.json`` (written after a successful fit and its export), is skipped with one log line;
a job whose ``last.ckpt`` carries that identity resumes from it into the same MLflow run; any
other job trains from scratch (a ``finished.json`` or ``last.ckpt`` of another config is
logged and replaced, never resumed). So running a stopped sweep's command again trains only what
is left, and a SLURM job requeued by submitit (pre-emption, ``max_num_timeout``) resumes itself.
``resume=sweep`` (default) does this in multiruns only; ``resume=auto`` in single runs too;
``resume=never`` always trains from scratch. An explicit ``ckpt_path`` wins over all of them.

The run goes to the experiment ``logger.experiment_name`` with a description (the family,
profile, data and command line, :func:`run_description`); its page in the MLflow UI is logged
at the end.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import time
import warnings
from contextlib import AbstractContextManager, ExitStack, nullcontext
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import lightning as L
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

from prg.checks import check_values
from prg.commands.cli import check_output
from prg.commands.settings import build
from prg.data.datamodule import PRGDataModule, read_manifest
from prg.errors import PRGError, UsageError
from prg.files import sha256_file, staged_outputs, write_json
from prg.locks import folder_locks
from prg.models.checkpoint import read_checkpoint, without_run_facts
from prg.models.module import PRGModule
from prg.resources import git_commit
from prg.tracking import (
    DESCRIPTION_TAG,
    PARENT_ENV,
    artifact_location,
    command_line,
    flatten,
    runs_page,
    tracking_uri,
)
from prg.training.settings import TrainSettings

log = logging.getLogger(__name__)


@dataclass
class TrainResult:
    """What a training run produced (``skipped``: it had finished before, ``resume``; no module
    or trainer then, the metrics are those it finished with)."""

    module: PRGModule | None
    trainer: L.Trainer | None
    metrics: dict[str, float]
    run_id: str | None
    best_checkpoint: str
    last_checkpoint: str
    skipped: bool = False


def train_settings(cfg: DictConfig) -> TrainSettings:
    """The model's modalities against the data's (``model``, ``data.loader.modalities``)."""
    values = {
        "model": cfg.model.name,
        "modalities": list(cfg.model.modalities),
        "provided": list(cfg.data.loader.modalities),
    }
    return build(TrainSettings, values, None)


def _build(node: Any, what: str, own_errors: bool = False, **kwargs: Any) -> Any:
    """instantiate() with a one-line UsageError naming the config node on bad values
    (``own_errors``: the project's own one-line errors as they are)."""
    from hydra.errors import InstantiationException

    try:
        return instantiate(node, **kwargs)
    except InstantiationException as err:
        cause = err.__cause__ or err
        if own_errors and isinstance(cause, PRGError):
            raise cause from None
        raise UsageError(f"{what} config: {' '.join(str(cause).split())}") from None


def build_datamodule(cfg: DictConfig) -> PRGDataModule:
    """The data loaders of the ``datamodule`` node (its ``_target_``: PRGDataModule), with the
    run's numbers from the options they are checked under: ``model.batch_size``,
    ``data.loader.num_workers`` and ``seed``."""
    return _build(
        cfg.datamodule,
        "datamodule",
        own_errors=True,  # PRGDataModule's refusals read as when it was built by hand
        batch_size=cfg.model.batch_size,
        num_workers=cfg.data.loader.num_workers,
        seed=cfg.seed,
        _convert_="all",
    )


def _manifest(cfg: DictConfig) -> tuple[dict[str, Any], str]:
    path = Path(cfg.paths.data_dir) / "prepared" / cfg.data.name / "manifest.json"
    if not path.is_file():
        raise UsageError(
            f"no prepared dataset at {path.parent}: run `prg-prepare data={cfg.data.name}` first"
        )
    return read_manifest(path.parent), sha256_file(path)


# Set to a rank by torchrun, SLURM and Lightning's launchers for the processes of a DDP run.
_RANK_VARIABLES = ("RANK", "LOCAL_RANK", "NODE_RANK", "SLURM_PROCID")


def _lock_outputs(cfg: DictConfig) -> AbstractContextManager:
    """Hold ``checkpoint_dir`` and ``export_dir`` for this run (:func:`prg.locks.folder_locks`):
    another run given either is refused in one line naming this one, so two runs never mix
    their checkpoints and exports. Only the first process of a DDP run (rank 0, the one that
    writes them) holds them; the others share them."""
    if any(os.environ.get(name, "0") != "0" for name in _RANK_VARIABLES):
        return nullcontext()
    folders = [(cfg.checkpoint_dir, "checkpoint_dir")]
    if cfg.get("export_dir"):
        folders.append((cfg.export_dir, "export_dir"))
    return folder_locks(folders)


def _resolve_ckpt_path(cfg: DictConfig) -> str | None:
    """``ckpt_path``, with ``last`` meaning ``${checkpoint_dir}/last.ckpt``, which must exist."""
    path = cfg.get("ckpt_path")
    if path != "last":
        return str(path) if path else None
    last = Path(cfg.checkpoint_dir) / "last.ckpt"
    if not last.is_file():
        raise UsageError(f"ckpt_path=last: no checkpoint {last} to resume from")
    return str(last)


RESUME_MODES = ("sweep", "auto", "never")
"""``resume``: ``auto`` skips a finished job and resumes an interrupted one, ``never`` always
trains from scratch, ``sweep`` is ``auto`` in a multirun and ``never`` in a single run."""
FINISHED = "finished.json"
"""The completion marker in ``checkpoint_dir``, written after a successful fit and its export."""
IDENTITY_KEY = "prg_job"
"""Where a checkpoint carries the :func:`job_identity` of the run that wrote it."""


def job_identity(cfg: DictConfig, manifest_hash: str) -> dict[str, Any]:
    """What makes two runs the same job: family, seed, profile, the data manifest's hash and the
    SHA-256 of the resolved config (JSON, sorted keys) without ``resume`` and ``ckpt_path``,
    which say how to run a job, not which."""
    resolved = OmegaConf.to_container(cfg, resolve=True)
    for key in ("resume", "ckpt_path"):
        resolved.pop(key, None)
    text = json.dumps(resolved, sort_keys=True, default=str)
    return {
        "family": str(cfg.model.name),
        "seed": int(cfg.seed),
        "profile": str(cfg.get("profile") or "default"),
        "data_manifest_sha256": manifest_hash,
        "config_sha256": hashlib.sha256(text.encode()).hexdigest(),
    }


def resume_mode(cfg: DictConfig) -> str:
    """``auto`` or ``never``: the ``resume`` option, ``sweep`` read as ``auto`` in a Hydra
    multirun job (any launcher, a requeued SLURM job included) and ``never`` elsewhere."""
    mode = cfg.get("resume") or "sweep"
    if mode not in RESUME_MODES:
        raise UsageError(f"unknown resume mode {mode}; accepted: {', '.join(RESUME_MODES)}")
    if mode != "sweep":
        return mode
    from hydra.core.hydra_config import HydraConfig
    from hydra.types import RunMode

    multirun = HydraConfig.initialized() and HydraConfig.get().mode == RunMode.MULTIRUN
    return "auto" if multirun else "never"


@dataclass
class JobPlan:
    """What :func:`plan_job` decided: ``skip``, ``resume`` (from ``checkpoint``) or ``fresh``."""

    action: str
    reason: str
    finished: dict[str, Any] | None = None  # skip: the marker
    checkpoint: dict[str, Any] | None = None  # resume: the loaded last.ckpt
    ckpt_path: str | None = None


def read_finished(checkpoint_dir: str | os.PathLike) -> dict[str, Any] | None:
    """The completion marker of ``checkpoint_dir`` (None: none, or not a readable one)."""
    try:
        marker = json.loads((Path(checkpoint_dir) / FINISHED).read_text())
    except (OSError, ValueError):
        return None
    return marker if isinstance(marker, dict) else None


def plan_job(cfg: DictConfig, identity: dict[str, Any]) -> JobPlan:
    """``resume=auto``: skip the job if ``finished.json`` matches ``identity`` (and the export,
    when ``export_dir`` is set, is there), else resume from ``last.ckpt`` if it carries
    ``identity``, else train from scratch. A marker or checkpoint of another identity (another
    config, data or profile in the same ``checkpoint_dir``) is never used: the job trains again."""
    folder = Path(cfg.checkpoint_dir)
    marker = read_finished(folder)
    if marker is not None and marker.get("identity") == identity:
        export = cfg.get("export_dir")
        if not export or (Path(export) / "metrics.json").is_file():
            return JobPlan("skip", f"finished before ({folder / FINISHED})", finished=marker)
        return JobPlan("fresh", f"finished before, but its export {export} is gone: training again")
    why = f"{folder / FINISHED} is of another config" if marker is not None else ""
    last = folder / "last.ckpt"
    if not last.is_file():
        return JobPlan("fresh", why or "nothing to resume")
    try:
        checkpoint = read_checkpoint(last)
    except UsageError as err:
        return JobPlan("fresh", f"{err}: training from scratch")
    if checkpoint.get(IDENTITY_KEY) != identity:
        return JobPlan("fresh", f"{last} is of another config: training from scratch")
    step = checkpoint.get("global_step", 0)
    return JobPlan("resume", f"resuming {last} at step {step}", None, checkpoint, str(last))


def _skipped(cfg: DictConfig, marker: dict[str, Any]) -> TrainResult:
    folder = Path(cfg.checkpoint_dir)
    metrics = {k: float(v) for k, v in (marker.get("metrics") or {}).items()}
    best, last = folder / "best.ckpt", folder / "last.ckpt"
    return TrainResult(
        None,
        None,
        metrics,
        marker.get("mlflow_run_id"),
        str(best) if best.is_file() else "",
        str(last) if last.is_file() else "",
        skipped=True,
    )


def run_description(cfg: DictConfig, manifest: dict[str, Any], manifest_hash: str) -> str:
    """The MLflow description of a training run (Markdown): what, on which data, how to rerun."""
    from prg.evaluation.reports import title

    every = cfg.trainer.get("log_every_n_steps")
    return "  \n".join(
        [
            f"**{title(cfg.model.name)}** (`{cfg.model.name}`) training, profile "
            f"`{cfg.get('profile') or 'default'}`, seed {cfg.seed}",
            f"Data: `{cfg.data.name}` ({manifest['source']}, manifest sha256 {manifest_hash[:12]})",
            f"Command: `{command_line('prg-train')}`",
            f"Curves: `train/*`, `val/*` per epoch, `train_steps/*` every {every} steps; "
            "compare families on `val/nll_per_dim_T`",
        ]
    )


def train(cfg: DictConfig) -> TrainResult:
    """Task: fit ``cfg.model`` on ``cfg.data`` with MLflow tracking and fixed-path checkpoints."""
    # mlflow.set_tracking_uri (called by Lightning's logger) exports MLFLOW_TRACKING_URI; keep
    # that from leaking into later runs of the same process (tests, notebooks, sweeps).
    saved = os.environ.get("MLFLOW_TRACKING_URI")
    try:
        with ExitStack() as held:  # the output folders' locks (_lock_outputs), until the end
            return _train(cfg, held)
    finally:
        if saved is None:
            os.environ.pop("MLFLOW_TRACKING_URI", None)
        else:
            os.environ["MLFLOW_TRACKING_URI"] = saved


def _train(cfg: DictConfig, held: ExitStack) -> TrainResult:
    check_values(cfg)
    train_settings(cfg)
    _fit_precision(cfg)
    manifest, manifest_hash = _manifest(cfg)
    check_output(cfg.checkpoint_dir, "checkpoint_dir")
    if cfg.get("export_dir"):
        check_output(cfg.export_dir, "export_dir")
    identity = job_identity(cfg, manifest_hash)
    resume, ckpt_path = None, _resolve_ckpt_path(cfg)
    if ckpt_path:
        resume = read_checkpoint(ckpt_path)
        family = resume["hyper_parameters"]["model"]["_target_"]
        if family != cfg.model.module.model._target_:
            raise UsageError(
                f"checkpoint {ckpt_path} holds a {family} model, not {cfg.model.name} "
                f"({cfg.model.module.model._target_}): pass the matching model=..."
            )
    held.enter_context(_lock_outputs(cfg))
    if not ckpt_path and resume_mode(cfg) == "auto":  # a sweep's job: done, to resume or new
        plan = plan_job(cfg, identity)
        job = f"{cfg.model.name} seed {cfg.seed}"
        if plan.action == "skip":
            run = (plan.finished or {}).get("mlflow_run_id")
            log.info(
                "%s: %s, MLflow run %s: skipped (resume=never retrains)", job, plan.reason, run
            )
            return _skipped(cfg, plan.finished or {})
        log.info("%s: %s", job, plan.reason)
        resume, ckpt_path = plan.checkpoint, plan.ckpt_path
    (Path(cfg.checkpoint_dir) / FINISHED).unlink(missing_ok=True)  # done again only at the end
    L.seed_everything(cfg.seed, workers=True)

    datamodule = build_datamodule(cfg)
    datamodule.setup("fit")  # now: a dataset the model cannot take fails before any run starts
    module_cfg = OmegaConf.to_container(cfg.model.module, resolve=True)
    module: PRGModule = _build(module_cfg, "model", _recursive_=False)

    uri = tracking_uri(cfg.logger.get("tracking_uri"), cfg.paths.root_dir)
    tags = {
        "prg.family": cfg.model.name,
        "prg.data.source": manifest["source"],
        "prg.data.name": cfg.data.name,
        "prg.data.manifest_sha256": manifest_hash,
        "prg.git_commit": git_commit(),
        "prg.experiment": str(cfg.get("profile") or "default"),
        "prg.seed": str(cfg.seed),
        DESCRIPTION_TAG: run_description(cfg, manifest, manifest_hash),
    }
    if os.environ.get(PARENT_ENV):
        tags["mlflow.parentRunId"] = os.environ[PARENT_ENV]
    logger = _build(
        cfg.logger,
        "logger",
        tracking_uri=uri,
        artifact_location=artifact_location(cfg.logger.artifact_location),
        run_id=(resume or {}).get("mlflow_run_id"),
        tags=tags,
    )
    callbacks = [_build(c, f"callbacks.{name}") for name, c in cfg.callbacks.items() if c]
    from prg.training.callbacks import (
        FitTime,
        JobIdentity,
        LastCheckpoint,
        MLflowRun,
        best_checkpoint,
    )

    callbacks.append(JobIdentity(identity, IDENTITY_KEY))  # what resume=auto matches
    fit_time = FitTime()
    callbacks.append(fit_time)
    callbacks.append(
        MLflowRun(
            config_yaml=OmegaConf.to_yaml(cfg, resolve=True),
            params=flatten(OmegaConf.to_container(cfg, resolve=True)),
            register_as=f"prg-{cfg.model.name}" if cfg.get("register_model") else None,
            log_model=bool(cfg.get("log_model", True)),
            dataset={
                "name": cfg.data.name,
                "digest": manifest_hash[:36],  # MLflow keeps at most 36 characters of a digest
                "source": str(Path(cfg.paths.data_dir, "prepared", cfg.data.name).resolve()),
            },
        )
    )
    trainer: L.Trainer = _build(cfg.trainer, "trainer", logger=logger, callbacks=callbacks)
    fit_time.begin()
    with warnings.catch_warnings():
        if trainer.world_size == 1:  # the loader goes on where it stopped, which Lightning
            # cannot see (LastCheckpoint, ResumableSampler): its warning that it does not
            # would mislead; under DDP it holds
            warnings.filterwarnings("ignore", "You're resuming from a checkpoint that ended")
        # weights_only: a resumed checkpoint is data, as read_checkpoint already checked it
        trainer.fit(module, datamodule=datamodule, ckpt_path=ckpt_path, weights_only=True)
    # the cost of the fit, CPU time of all threads; a resumed fit's earlier starts included
    metrics = {k: float(v) for k, v in trainer.callback_metrics.items()}
    metrics["fit_cpu_s"], metrics["fit_wall_s"] = fit_time.elapsed()
    metrics["fit_starts"] = float(fit_time.starts)
    metrics["epochs"] = float(trainer.current_epoch)
    metrics["steps"] = float(trainer.global_step)
    best = best_checkpoint(trainer)
    last = next((str(c.path) for c in callbacks if isinstance(c, LastCheckpoint)), "")
    if trainer.fast_dev_run:  # Lightning swapped the loggers out: no run was started, none made
        log.info("fast dev run (debug=fdr): no MLflow run, no checkpoints")
        return TrainResult(module, trainer, metrics, None, best, last)
    if cfg.get("export_dir") and best and trainer.is_global_zero:  # DDP: rank 0 only
        history = history_rows(logger.experiment, logger.run_id)
        _export(Path(cfg.export_dir), best, metrics, logger.run_id, cfg, history)
    if trainer.is_global_zero:
        if trainer.state.finished:
            _write_finished(cfg, identity, logger.run_id, metrics)
        log.info("MLflow run %s: %s", logger.run_id, runs_page(logger.experiment_id))
    return TrainResult(module, trainer, metrics, logger.run_id, best, last)


def _write_finished(cfg: DictConfig, identity: dict[str, Any], run_id: str, metrics) -> None:
    """``finished.json``: this job's identity, run and metrics, after its fit and export, so that
    ``resume=auto`` skips it (a kill before this line leaves a job that resumes instead)."""
    write_json(
        Path(cfg.checkpoint_dir) / FINISHED,
        {
            "identity": identity,
            "mlflow_run_id": run_id,
            "finished_at": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            "metrics": {k: v for k, v in sorted(metrics.items()) if v == v},  # no NaN in JSON
        },
    )


HISTORY_METRICS = ("train/loss", "val/loss", "val/nll_per_dim_T")
"""The per-epoch curves of ``history.csv`` (every family logs them)."""


def history_rows(client, run_id: str) -> list[dict[str, float]]:
    """The run's per-epoch curves from its MLflow metric history (a resumed run's earlier epochs
    included): one row per validation, ``epoch``, ``step`` and each of :data:`HISTORY_METRICS`
    (named as in ``metrics.json``: ``val/loss`` -> ``val_loss``)."""
    epoch_at = {m.step: int(m.value) for m in client.get_metric_history(run_id, "epoch")}
    rows: dict[int, dict[str, float]] = {}
    for key in HISTORY_METRICS:
        for m in client.get_metric_history(run_id, key):
            row = rows.setdefault(m.step, {"epoch": epoch_at.get(m.step, -1), "step": m.step})
            row[key.replace("/", "_")] = m.value
    return [rows[step] for step in sorted(rows) if "val_loss" in rows[step]]


def _fit_precision(cfg: DictConfig) -> None:
    """bf16 autocast only where this machine has bf16 kernels (:mod:`prg.training.precision`)."""
    from prg.training.precision import cpu_has_bf16, trains_on_gpu, usable_precision

    asked = str(cfg.trainer.precision)
    usable = usable_precision(asked, trains_on_gpu(cfg.trainer.accelerator), cpu_has_bf16())
    if usable != asked:
        log.warning(
            "trainer.precision=%s: this CPU has no bf16 kernels, where autocast emulates bf16 "
            "many times slower; training in %s",
            asked,
            usable,
        )
        cfg.trainer.precision = usable


def _export(
    folder: Path, best: str, metrics: dict[str, float], run_id: str, cfg, history: list[dict]
) -> None:
    """Write the best checkpoint without its run facts to ``<folder>/model.ckpt``
    (:func:`~prg.models.checkpoint.without_run_facts`: the same training gives the same bytes),
    ``metrics.json`` (with the MLflow run id) and the per-epoch curves ``history.csv`` (DVC
    metrics and plots); all are complete before any replaces the previous export."""
    import torch

    with staged_outputs(folder) as staging:
        torch.save(without_run_facts(read_checkpoint(best)), staging / "model.ckpt")
        columns = ["epoch", "step", *(k.replace("/", "_") for k in HISTORY_METRICS)]
        lines = [",".join(columns)]
        lines += [",".join(f"{row.get(c, '')}" for c in columns) for row in history]
        (staging / "history.csv").write_text("\n".join(lines) + "\n")
        write_json(
            staging / "metrics.json",
            {
                "family": cfg.model.name,
                "mlflow_run_id": run_id,
                "seed": cfg.seed,
                **{k.replace("/", "_"): round(v, 4) for k, v in sorted(metrics.items())},
            },
        )


if __name__ == "__main__":
    from prg.commands.entry import train

    train()
