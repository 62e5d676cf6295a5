"""Lightning callbacks: the checkpoint to resume from, MLflow run bookkeeping, training curves
every few steps, a validation metric shared by every family, generation figures."""

from __future__ import annotations

import logging
import math
import os
import tempfile
import time
from pathlib import Path
from typing import Any

import lightning as L
import torch
from lightning.pytorch.callbacks import Checkpoint, EarlyStopping, ModelCheckpoint
from lightning.pytorch.loggers import MLFlowLogger

from prg.files import atomic_path
from prg.models.modalities import MODALITIES, TRAJ
from prg.plotting import pyplot
from prg.serving import log_writer_model, register_version

log = logging.getLogger(__name__)


def _mlflow(trainer: L.Trainer) -> MLFlowLogger | None:
    return next((lg for lg in trainer.loggers if isinstance(lg, MLFlowLogger)), None)


def best_checkpoint(trainer: L.Trainer) -> str:
    """Path of the best checkpoint of the run's ``ModelCheckpoint`` ("" when none)."""
    best = next((c for c in trainer.callbacks if isinstance(c, ModelCheckpoint)), None)
    return best.best_model_path if best else ""


class LastCheckpoint(Checkpoint):
    """Keeps ``<dirpath>/last.ckpt``, the checkpoint to resume from after a crash or a kill
    (``prg-train ckpt_path=last``). It is written

    * every ``every_n_train_steps`` optimizer steps inside an epoch (0: never), so a kill loses
      at most that many steps; Lightning resumes such a checkpoint mid-epoch, running only the
      epoch's remaining batches;
    * at the end of every epoch, after validation and after the module has computed the epoch's
      means (a :class:`Checkpoint` runs its epoch-end hook after the module's), so a resumed run
      logs no epoch twice (except after a kill in the fraction of a second between the logging
      of an epoch's ``val/*`` and this save: that epoch's ``val/*`` then appears twice, at the
      same step);
    * at the end of training, when that is not an epoch end (``trainer.max_steps``).

    The file is written next to its final name and moved into place, so a kill during a write
    leaves the previous ``last.ckpt`` intact. The per-epoch loss sums the module has accumulated
    so far travel in the checkpoint, so the interrupted epoch's ``train/*`` averages all of its
    batches. So do the random state a training draws its noise from (torch's global generators,
    put back before the first batch after the resume) and the training shuffle's
    (:class:`prg.data.datamodule.ResumableSampler`: the interrupted epoch goes on in its own
    order, without the batches already trained on), so on one process a resumed run trains on
    what an uninterrupted one does and ends with the same weights. (Under DDP Lightning shuffles
    with its own sampler, seeded per epoch: a resume at an epoch's end keeps the order, one
    mid-epoch does not.) Lightning's ``ModelCheckpoint(save_last=True)`` is not used for this:
    since Lightning 2.6 it refreshes ``last.ckpt`` only when a top-k checkpoint is saved, that
    is when the monitored loss improves.
    """

    FILENAME = "last.ckpt"

    def __init__(self, dirpath: str | os.PathLike, every_n_train_steps: int = 0):
        if isinstance(every_n_train_steps, bool) or not isinstance(every_n_train_steps, int):
            raise TypeError(f"every_n_train_steps must be an integer, got {every_n_train_steps!r}")
        if every_n_train_steps < 0:
            raise ValueError(f"every_n_train_steps must be >= 0, got {every_n_train_steps}")
        self.path = Path(dirpath) / self.FILENAME
        self.every_n_train_steps = every_n_train_steps
        self._saved_step = -1
        self._batches_done = 0  # of the current epoch, at the save
        self._random_state: dict[str, Any] | None = None  # to put back at the next batch

    def save(self, trainer: L.Trainer) -> None:
        if trainer.fast_dev_run:  # a smoke test of the loop, nothing to resume (as ModelCheckpoint)
            return
        if trainer.is_global_zero:
            with atomic_path(self.path) as tmp:
                # every rank calls it; the strategy writes on rank 0
                trainer.save_checkpoint(tmp, weights_only=False)
        else:
            trainer.save_checkpoint(self.path, weights_only=False)  # writes nothing here
        trainer.strategy.barrier("LastCheckpoint.save")
        self._saved_step = trainer.global_step

    def on_train_batch_end(self, trainer, pl_module, outputs, batch, batch_idx) -> None:
        every = self.every_n_train_steps
        last_batch = trainer.fit_loop.epoch_loop.batch_progress.is_last_batch
        self._batches_done = batch_idx + 1
        if every and trainer.global_step % every == 0 and not last_batch:
            self.save(trainer)  # at the last batch, the epoch-end save follows validation

    def on_train_epoch_end(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        self._batches_done = 0  # the next epoch starts afresh
        self.save(trainer)

    def on_train_batch_start(self, trainer, pl_module, batch, batch_idx) -> None:
        if self._random_state is not None:  # the first batch after a resume
            set_random_state(self._random_state)
            self._random_state = None

    def on_train_end(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        if trainer.global_step != self._saved_step:
            self.save(trainer)

    def on_save_checkpoint(self, trainer, pl_module, checkpoint: dict[str, Any]) -> None:
        # PRGModule sums each loss term over an epoch's batches and logs the means at its end
        checkpoint["prg_epoch_sums"] = {
            "sums": getattr(pl_module, "_sums", {}),
            "counts": getattr(pl_module, "_counts", {}),
        }
        checkpoint["prg_random_state"] = random_state()
        sampler = getattr(trainer.datamodule, "train_sampler", None)
        if sampler is not None:
            checkpoint["prg_training_order"] = {
                "generator": sampler.generator.get_state(),
                "epoch": sampler.epoch_state,
                "samples_done": self._batches_done * trainer.train_dataloader.batch_size,
            }

    def on_load_checkpoint(self, trainer, pl_module, checkpoint: dict[str, Any]) -> None:
        state = checkpoint.get("prg_epoch_sums")
        if state is not None and hasattr(pl_module, "_sums"):
            pl_module._sums = {
                split: {k: v.to(pl_module.device) for k, v in terms.items()}
                for split, terms in state["sums"].items()
            }
            pl_module._counts = dict(state["counts"])
        self._random_state = checkpoint.get("prg_random_state")
        order = checkpoint.get("prg_training_order")
        datamodule = getattr(trainer, "datamodule", None)
        if order is not None and hasattr(datamodule, "resume_order") and trainer.world_size == 1:
            datamodule.resume_order = order


def random_state() -> dict[str, Any]:
    """The state of torch's global generators (CPU, and CUDA where there is one): a training
    draws its noise (reparameterisation, dropout, image shifts) from them, never from numpy's
    or Python's."""
    state = {"torch": torch.get_rng_state()}
    if torch.cuda.is_available():
        state["cuda"] = torch.cuda.get_rng_state_all()
    return state


def set_random_state(state: dict[str, Any]) -> None:
    """Put back what :func:`random_state` returned."""
    torch.set_rng_state(state["torch"])
    if "cuda" in state and torch.cuda.is_available():
        torch.cuda.set_rng_state_all(state["cuda"])


class JobIdentity(L.Callback):
    """Writes the identity of the job (``prg.commands.train.job_identity``: family, seed, profile,
    data and config hashes) into every checkpoint under ``key``, so that ``prg-train resume=auto``
    resumes a ``last.ckpt`` only into the job that wrote it."""

    def __init__(self, identity: dict[str, Any], key: str = "prg_job"):
        self.identity = dict(identity)
        self.key = key

    def on_save_checkpoint(self, trainer, pl_module, checkpoint: dict[str, Any]) -> None:
        checkpoint[self.key] = dict(self.identity)


class FitTime(L.Callback):
    """CPU seconds (all threads of the process) and wall seconds of a fit, summed over its
    starts: the time so far goes into every checkpoint, so a fit resumed from one adds its own
    time to the earlier starts' time up to that checkpoint (work done after it, lost and done
    again, counts once). :meth:`begin` starts the clocks, right before ``trainer.fit``."""

    def __init__(self) -> None:
        self.earlier_cpu_s = self.earlier_wall_s = 0.0
        self.starts = 1
        self._clocks = (time.process_time(), time.perf_counter())

    def begin(self) -> None:
        self._clocks = (time.process_time(), time.perf_counter())

    def elapsed(self) -> tuple[float, float]:
        """(CPU s, wall s) of the fit so far, earlier starts included."""
        cpu0, wall0 = self._clocks
        return (
            self.earlier_cpu_s + time.process_time() - cpu0,
            self.earlier_wall_s + time.perf_counter() - wall0,
        )

    def state_dict(self) -> dict[str, Any]:
        cpu_s, wall_s = self.elapsed()
        return {"cpu_s": cpu_s, "wall_s": wall_s, "starts": self.starts}

    def load_state_dict(self, state_dict: dict[str, Any]) -> None:
        self.earlier_cpu_s = float(state_dict["cpu_s"])
        self.earlier_wall_s = float(state_dict["wall_s"])
        self.starts = int(state_dict["starts"]) + 1


class SystemMetrics(L.Callback):
    """CPU, memory, disk and network use (and GPU, where one is monitored) of the training run,
    logged by MLflow's own system-metrics monitor as ``system/*`` metrics of the run, every
    ``sampling_interval_s`` seconds from the start of training to its end.

    MLflow starts this monitor itself only for runs opened with ``mlflow.start_run(
    log_system_metrics=True)``; Lightning's logger opens its run through the client, so the
    monitor is attached here to that run. It needs ``psutil`` (installed with MLflow here); without
    it the callback does nothing. A resumed run continues its steps (``resume_logging``). Off:
    ``callbacks.system_metrics=null``.
    """

    def __init__(self, sampling_interval_s: float = 10.0):
        if not sampling_interval_s > 0:
            raise ValueError(f"sampling_interval_s must be > 0, got {sampling_interval_s!r}")
        self.sampling_interval_s = sampling_interval_s
        self._monitor = None

    def on_train_start(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        logger = _mlflow(trainer)
        if logger is None or trainer.global_rank != 0:
            return
        try:
            import psutil  # noqa: F401  (the monitor's dependency)
            from mlflow.system_metrics.system_metrics_monitor import SystemMetricsMonitor
        except ImportError:
            log.debug("psutil is not installed: no system metrics")
            return
        self._monitor = SystemMetricsMonitor(
            logger.run_id,
            sampling_interval=self.sampling_interval_s,
            resume_logging=trainer.global_step > 0,
            tracking_uri=logger._tracking_uri,
        )
        self._monitor.start()

    def _finish(self) -> None:
        if self._monitor is not None:
            self._monitor.finish()
            self._monitor = None

    def on_train_end(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        self._finish()

    def on_exception(self, trainer: L.Trainer, pl_module: L.LightningModule, exc) -> None:
        self._finish()


def _log_dataset(client, run_id: str, name: str, digest: str, source: str) -> None:
    """The prepared dataset as the run's training input (MLflow's dataset lineage: the run page's
    *Datasets used*, ``search_runs`` by dataset): a :class:`~mlflow.data.meta_dataset.MetaDataset`,
    as the data are not loaded as one table, whose digest is the manifest's SHA-256."""
    from mlflow.data.meta_dataset import MetaDataset
    from mlflow.data.sources import LocalArtifactDatasetSource
    from mlflow.entities import DatasetInput, InputTag

    dataset = MetaDataset(LocalArtifactDatasetSource(source), name=name, digest=digest)
    context = InputTag(key="mlflow.data.context", value="training")
    client.log_inputs(run_id, datasets=[DatasetInput(dataset._to_mlflow_entity(), [context])])


class MLflowRun(L.Callback):
    """Bookkeeping of the MLflow run: the composed config (artifact and flattened params) and the
    dataset at the start, the run id inside every checkpoint (so resuming continues the same run),
    the best checkpoint at the end as an artifact and as an MLflow model (``log_model``:
    :func:`prg.serving.log_writer_model`), and optionally a registered version of that model."""

    def __init__(
        self,
        config_yaml: str = "",
        params: dict[str, Any] | None = None,
        register_as: str | None = None,
        dataset: dict[str, str] | None = None,
        log_model: bool = True,
    ):
        self.config_yaml = config_yaml
        self.params = params or {}
        self.register_as = register_as
        self.log_model = log_model  # the best checkpoint as an MLflow model (prg.serving)
        self.dataset = dataset  # name, digest, source: logged as the run's training input

    def on_train_start(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        # on_train_start, not on_fit_start: a resumed trainer's global_step is restored by now
        logger = _mlflow(trainer)
        if logger is None or trainer.global_rank != 0:
            return
        client, run_id = logger.experiment, logger.run_id
        logged = client.get_run(run_id).data.params
        resumed = bool(client.list_artifacts(run_id, "config"))  # this run was started before
        if resumed:  # a killed run stays RUNNING, a crashed one FAILED: running again now
            client.update_run(run_id, status="RUNNING")
        name = (
            f"config/config-resume-{trainer.global_step}.yaml" if resumed else "config/config.yaml"
        )
        if self.config_yaml:
            client.log_text(run_id, self.config_yaml, name)
        params = {k: str(v) for k, v in self.params.items()}
        changed = sorted(k for k in params if k in logged and logged[k] != params[k][:6000])
        if changed:  # MLflow params are immutable: keep the first values, note what changed
            client.set_tag(run_id, f"prg.resumed_at_step_{trainer.global_step}", ", ".join(changed))
        logger.log_hyperparams({k: v for k, v in params.items() if k not in logged})
        if self.dataset and not resumed:
            _log_dataset(client, run_id, **self.dataset)

    def on_save_checkpoint(self, trainer, pl_module, checkpoint: dict[str, Any]) -> None:
        logger = _mlflow(trainer)
        if logger is not None:
            checkpoint["mlflow_run_id"] = logger.run_id
            checkpoint["mlflow_tracking_uri"] = logger._tracking_uri

    def on_fit_end(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        logger = _mlflow(trainer)
        best = best_checkpoint(trainer)
        if logger is None or trainer.global_rank != 0 or not best or not Path(best).is_file():
            return
        logger.experiment.log_artifact(logger.run_id, best, "checkpoints")
        if not self.log_model:
            return
        model_uri = log_writer_model(best, logger.run_id, logger._tracking_uri)
        log.info("logged the MLflow model %s (prg.serving.WriterModel)", model_uri)
        if self.register_as:
            # named as in the export's metrics.json (val/loss -> val_loss)
            metrics = {k.replace("/", "_"): float(v) for k, v in trainer.callback_metrics.items()}
            version = register_version(
                self.register_as, logger.run_id, logger._tracking_uri, metrics
            )
            log.info("registered %s version %s", self.register_as, version)


class StepMeans(L.Callback):
    """Training curves with enough points: every ``trainer.log_every_n_steps`` optimizer steps,
    the mean of each loss term over those steps, logged to MLflow as ``train_steps/<term>`` at
    the step of the window's last batch (0-based, as Lightning logs the epoch means
    ``train/<term>``, which stay as they are).

    Nothing is added to the training step: the window's sums are the growth of the per-epoch
    sums :class:`~prg.models.module.PRGModule` accumulates anyway, and a window across an epoch's
    end carries that epoch's tail over. Each window costs one small tensor reduction (the mean
    over DDP ranks) and one MLflow write. The open window travels in checkpoints, so a resumed
    run continues it."""

    def __init__(self) -> None:
        self._window: dict[str, torch.Tensor] = {}  # sums of the open window (earlier epochs)
        self._window_count = 0
        self._seen: dict[str, torch.Tensor] = {}  # the module's sums when last read, this epoch
        self._seen_count = 0
        self._logged_step = -1

    def _read(self, pl_module: L.LightningModule) -> None:
        """Add the module's sums since the last read to the open window."""
        sums = getattr(pl_module, "_sums", {}).get("train", {})
        count = getattr(pl_module, "_counts", {}).get("train", 0)
        for key, value in sums.items():
            grown = value - self._seen.get(key, 0.0)
            self._window[key] = self._window.get(key, 0.0) + grown
        self._window_count += count - self._seen_count
        self._seen, self._seen_count = {k: v.detach().clone() for k, v in sums.items()}, count

    def on_train_batch_end(self, trainer, pl_module, outputs, batch, batch_idx) -> None:
        every, step = trainer.log_every_n_steps, trainer.global_step
        # (with gradient accumulation several batches end at one optimizer step: the first logs)
        if not every or not step or step % every or step == self._logged_step:
            return
        self._read(pl_module)
        self._logged_step = step
        if not self._window_count:  # nothing trained since the last window (every rank alike)
            return
        keys = sorted(self._window)
        means = torch.stack([self._window[k].float() for k in keys]) / self._window_count
        means = trainer.strategy.reduce(means, reduce_op="mean")  # every rank, the same step
        self._window, self._window_count = {}, 0
        logger = _mlflow(trainer)
        if logger is not None and trainer.is_global_zero:
            metrics = {f"train_steps/{k}": v for k, v in zip(keys, means.tolist())}
            logger.log_metrics(metrics, step=step - 1)

    def on_train_epoch_end(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        # before the module's hook (Lightning calls callbacks that monitor nothing first), which
        # logs the epoch's means and clears its sums
        self._read(pl_module)
        self._seen, self._seen_count = {}, 0

    def on_train_start(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        device = pl_module.device  # a resumed window was loaded on the CPU
        self._window = {k: v.to(device) for k, v in self._window.items()}
        self._seen = {k: v.to(device) for k, v in self._seen.items()}

    def state_dict(self) -> dict[str, Any]:
        return {
            "window": self._window,
            "window_count": self._window_count,
            "seen": self._seen,
            "seen_count": self._seen_count,
        }

    def load_state_dict(self, state_dict: dict[str, Any]) -> None:
        self._window, self._window_count = dict(state_dict["window"]), state_dict["window_count"]
        self._seen, self._seen_count = dict(state_dict["seen"]), state_dict["seen_count"]


class TrajectoryNLL(L.Callback):
    """The validation trajectories' NLL per dimension, one number every family logs alike.

    Logged as ``val/nll_per_dim_traj`` (in MLflow ``val/nll_per_dim_T``), to compare families in
    one column.

    The negative log-likelihood of each validation trajectory under the model's own Gaussian
    (``traj_std``, 0.1 in every family's config), decoded from the posterior mean given the
    trajectory (the CVAE: and its label, which its encoder needs), per coordinate: the sum over
    the 200 coordinates divided by 200, averaged over the validation samples. It is a
    reconstruction likelihood, not the marginal log p(x_T) (the CVAE has none; ``prg-evaluate``
    estimates Table I's cells): lower is better, and a constant plus 50 x the mean squared
    error at std 0.1. Costs one encode and decode of each validation batch."""

    KEY = f"val/nll_per_dim_{TRAJ}"

    def on_validation_epoch_start(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        self._sum: torch.Tensor | float = 0.0
        self._count = 0

    def on_validation_batch_end(
        self, trainer, pl_module, outputs, batch, batch_idx, dataloader_idx=0
    ) -> None:
        model = pl_module.model
        given = min((s for s in model.accepted_inputs if TRAJ in s), key=len, default=None)
        if given is None or TRAJ not in model.generated_modalities:
            return
        mean = model.generate({m: batch[m] for m in given}, TRAJ)[0].float()
        self._sum = self._sum - model.likelihoods.log_prob(TRAJ, mean, batch[TRAJ]).sum()
        self._count += len(mean)

    def on_validation_epoch_end(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        if self._count:  # sync_dist: the mean over DDP ranks (equal shards)
            dims = math.prod(MODALITIES[TRAJ].shape)
            pl_module.log(self.KEY, self._sum / (self._count * dims), sync_dist=True)


class GenerationFigures(L.Callback):
    """Every ``every_n_epochs`` validation epochs and at the end of training: reconstructions of
    each modality and the cross-modal generations the family supports (label -> trajectory for
    all 62 classes, image -> trajectory, trajectory -> image), logged to MLflow as PNGs of
    ``dpi`` dots per inch.

    The examples are ``n_examples`` validation samples of classes spread over the alphabet
    (:func:`~prg.training.generation_figures.spread_examples`: digits, upper- and lowercase
    letters), picked with ``seed``: the same ones at every epoch and, whatever the run's seed,
    in every run on the same data, so figures compare across runs. Their classes are in
    :attr:`example_classes` once drawn."""

    def __init__(self, every_n_epochs: int = 5, n_examples: int = 8, dpi: int = 150, seed: int = 0):
        self.every_n_epochs = every_n_epochs
        self.n_examples = n_examples
        self.dpi = dpi
        self.seed = seed
        self.example_indices: list[int] | None = None
        self.example_classes: list[str] = []

    def _examples(self, datamodule: L.LightningDataModule) -> dict[str, torch.Tensor]:
        """The chosen validation samples as one batch (chosen on the first call)."""
        dataset = datamodule.val_dataloader().dataset
        if self.example_indices is None:
            from prg.alphabet import ALPHABET
            from prg.data.store import load_split
            from prg.models.modalities import LABEL
            from prg.training.generation_figures import spread_examples

            # every split holds the labels, also for families that do not model them
            labels = load_split(Path(datamodule.root) / "val.npz")[LABEL]
            self.example_indices = spread_examples(labels, self.n_examples, self.seed).tolist()
            self.example_classes = [ALPHABET[int(labels[i])] for i in self.example_indices]
        return dataset.__getitems__(self.example_indices)

    def on_validation_epoch_end(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        epoch = trainer.current_epoch + 1
        if trainer.sanity_checking or not self.every_n_epochs or epoch % self.every_n_epochs:
            return
        self.log_figures(trainer, pl_module, f"epoch_{epoch:03d}")

    def on_fit_end(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        self.log_figures(trainer, pl_module, "final")

    def log_figures(self, trainer: L.Trainer, pl_module: L.LightningModule, tag: str) -> None:
        logger = _mlflow(trainer)
        if logger is None or trainer.global_rank != 0 or trainer.datamodule is None:
            return
        from prg.training.generation_figures import generation_figures

        batch = self._examples(trainer.datamodule)
        batch = {k: v.to(pl_module.device) for k, v in batch.items()}
        was_training = pl_module.training
        pl_module.eval()
        try:
            figures = generation_figures(pl_module.model, batch, self.example_classes)
        finally:
            pl_module.train(was_training)
        plt = pyplot()

        with tempfile.TemporaryDirectory() as tmp:
            for name, fig in figures.items():
                path = os.path.join(tmp, f"{name}.png")
                fig.savefig(path, dpi=self.dpi)
                plt.close(fig)
                logger.experiment.log_artifact(logger.run_id, path, f"figures/{tag}")


class AnnealedEarlyStopping(EarlyStopping):
    """Early stopping that watches only the last part of a run: from the epoch past
    ``start_fraction`` of ``max_epochs`` on (all of EarlyStopping's options otherwise).

    Under a one-cycle schedule the validation loss stalls while the learning rate is near its
    peak and falls as it anneals; counting patience from the first epoch stopped AVAE(T,S) at
    epoch 11 of 40 with a validation loss of -167, where the full schedule reaches -197 in 16."""

    def __init__(self, start_fraction: float = 0.5, **kwargs: Any):
        super().__init__(**kwargs)
        if not 0.0 <= start_fraction < 1.0:
            raise ValueError(f"start_fraction must be in [0, 1), got {start_fraction!r}")
        self.start_fraction = start_fraction

    def _watching(self, trainer: L.Trainer) -> bool:
        return trainer.current_epoch + 1 > self.start_fraction * trainer.max_epochs

    def on_validation_end(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        if self._watching(trainer):
            super().on_validation_end(trainer, pl_module)

    def on_train_epoch_end(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        if self._watching(trainer):
            super().on_train_epoch_end(trainer, pl_module)
