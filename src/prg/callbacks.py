"""Lightning callbacks: MLflow run bookkeeping and generation figures."""

from __future__ import annotations

import contextlib
import logging
import os
import tempfile
from pathlib import Path
from typing import Any

import lightning as L
from lightning.pytorch.loggers import MLFlowLogger

log = logging.getLogger(__name__)


def _mlflow(trainer: L.Trainer) -> MLFlowLogger | None:
    return next((lg for lg in trainer.loggers if isinstance(lg, MLFlowLogger)), None)


class MLflowRun(L.Callback):
    """Bookkeeping of the MLflow run: the composed config (artifact and flattened params) at the
    start, the run id inside every checkpoint (so resuming continues the same run), the best
    checkpoint at the end, and optionally a registered model version."""

    def __init__(
        self,
        config_yaml: str = "",
        params: dict[str, Any] | None = None,
        register_as: str | None = None,
    ):
        self.config_yaml = config_yaml
        self.params = params or {}
        self.register_as = register_as

    def on_fit_start(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        logger = _mlflow(trainer)
        if logger is None or trainer.global_rank != 0:
            return
        client, run_id = logger.experiment, logger.run_id
        logged = client.get_run(run_id).data.params  # non-empty when resuming this run
        name = (
            "config/config.yaml"
            if not logged
            else f"config/config-resume-{trainer.global_step}.yaml"
        )
        if self.config_yaml:
            client.log_text(run_id, self.config_yaml, name)
        params = {k: str(v) for k, v in self.params.items()}
        changed = sorted(k for k in params if k in logged and logged[k] != params[k][:6000])
        if changed:  # MLflow params are immutable: keep the first values, note what changed
            client.set_tag(run_id, f"prg.resumed_at_step_{trainer.global_step}", ", ".join(changed))
        logger.log_hyperparams({k: v for k, v in params.items() if k not in logged})

    def on_save_checkpoint(self, trainer, pl_module, checkpoint: dict[str, Any]) -> None:
        logger = _mlflow(trainer)
        if logger is not None:
            checkpoint["mlflow_run_id"] = logger.run_id
            checkpoint["mlflow_tracking_uri"] = logger._tracking_uri

    def on_fit_end(self, trainer: L.Trainer, pl_module: L.LightningModule) -> None:
        logger = _mlflow(trainer)
        best = trainer.checkpoint_callback.best_model_path if trainer.checkpoint_callback else ""
        if logger is None or trainer.global_rank != 0 or not best or not Path(best).is_file():
            return
        logger.experiment.log_artifact(logger.run_id, best, "checkpoints")
        if self.register_as:
            from mlflow import MlflowClient
            from mlflow.exceptions import MlflowException

            client = MlflowClient(logger._tracking_uri)
            with contextlib.suppress(MlflowException):  # already registered: add a version
                client.create_registered_model(self.register_as)
            run = client.get_run(logger.run_id)
            source = f"{run.info.artifact_uri}/checkpoints/{Path(best).name}"
            version = client.create_model_version(self.register_as, source, logger.run_id)
            log.info("registered %s version %s", self.register_as, version.version)


class GenerationFigures(L.Callback):
    """Every ``every_n_epochs`` validation epochs and at the end of training: reconstructions of
    each modality and the cross-modal generations the family supports (label -> trajectory for
    all 62 classes, image -> trajectory, trajectory -> image), logged to MLflow as PNGs."""

    def __init__(self, every_n_epochs: int = 5, n_examples: int = 8):
        self.every_n_epochs = every_n_epochs
        self.n_examples = n_examples

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
        from prg.figures import generation_figures

        loader = trainer.datamodule.val_dataloader()
        batch = next(iter(loader))
        batch = {k: v[: self.n_examples].to(pl_module.device) for k, v in batch.items()}
        was_training = pl_module.training
        pl_module.eval()
        try:
            figures = generation_figures(pl_module.model, batch)
        finally:
            pl_module.train(was_training)
        import matplotlib.pyplot as plt

        with tempfile.TemporaryDirectory() as tmp:
            for name, fig in figures.items():
                path = os.path.join(tmp, f"{name}.png")
                fig.savefig(path, dpi=72)
                plt.close(fig)
                logger.experiment.log_artifact(logger.run_id, path, f"figures/{tag}")
