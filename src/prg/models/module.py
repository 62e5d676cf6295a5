"""One LightningModule for every family.

The module is built from plain config dicts (``model`` and ``optimizer``, each with a
``_target_``), saved as hyper-parameters, so ``PRGModule.load_from_checkpoint(path)`` rebuilds
any family with no other information. Metrics are logged per epoch as ``train/<term>`` and
``val/<term>`` for every loss term the family returns.
"""

from __future__ import annotations

from typing import Any

import lightning as L
import torch
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

from prg.errors import UsageError
from prg.models.base import MultimodalVAE
from prg.models.components import TrajectoryDecoder, shift_images


def _plain(cfg: Any) -> dict[str, Any]:
    return OmegaConf.to_container(cfg, resolve=True) if isinstance(cfg, DictConfig) else dict(cfg)


class PRGModule(L.LightningModule):
    """Wraps a :class:`~prg.models.base.MultimodalVAE`.

    Parameters
    ----------
    model : dict
        Config of the family (``_target_`` and its arguments), e.g. ``conf/model/muse.yaml``.
    optimizer : dict
        Partial optimizer config (``_target_: torch.optim.Adam``, ``_partial_: true``, ``lr``).
    scheduler : dict, optional
        Partial learning-rate scheduler config stepped once per optimizer step, called as
        ``scheduler(optimizer, total_steps=<the run's optimizer steps>)`` (e.g.
        ``torch.optim.lr_scheduler.OneCycleLR``); ``None``: a constant learning rate.
    kl_warmup_epochs : float
        Linear warm-up of the latent regularisers of the families that have one (``kl_scale``:
        MUSE's top-level KL, beta, and subset symmetric KL, delta, see :mod:`prg.models.muse`;
        MVAE's KL terms, see :mod:`prg.models.mvae`) over this many epochs, updated every step
        (fractions allowed; 0: none).
    zero_init_trajectory : bool
        Start every trajectory decoder's output layer at zero
        (:meth:`~prg.models.components.TrajectoryDecoder.zero_output_layer`): smooth letters
        from the first steps instead of a white-noise pattern that training removes slowly.
    image_shift : int
        Denoising training of image encoders: in training steps each image the encoders see is
        moved by a random whole-pixel offset of up to this many pixels per axis
        (:func:`~prg.models.components.shift_images`), while the reconstruction targets stay the
        unshifted images (0: off). Decoders and validation are unchanged.
    """

    def __init__(
        self,
        model: dict[str, Any],
        optimizer: dict[str, Any],
        scheduler: dict[str, Any] | None = None,
        kl_warmup_epochs: float = 0,
        zero_init_trajectory: bool = False,
        image_shift: int = 0,
    ):
        super().__init__()
        model, optimizer = _plain(model), _plain(optimizer)  # checkpoints hold plain containers
        scheduler = _plain(scheduler) if scheduler else None
        self.save_hyperparameters(
            {
                "model": model,
                "optimizer": optimizer,
                "scheduler": scheduler,
                "kl_warmup_epochs": kl_warmup_epochs,
                "zero_init_trajectory": zero_init_trajectory,
                "image_shift": image_shift,
            }
        )
        self.model: MultimodalVAE = instantiate(model, _convert_="all")
        if zero_init_trajectory:
            for decoder in self.model.modules():
                if isinstance(decoder, TrajectoryDecoder):
                    decoder.zero_output_layer()
        self._sums: dict[str, dict[str, torch.Tensor]] = {}
        self._counts: dict[str, int] = {}
        if isinstance(kl_warmup_epochs, bool) or not (
            isinstance(kl_warmup_epochs, int | float) and kl_warmup_epochs >= 0
        ):
            raise UsageError(f"kl_warmup_epochs must be a number >= 0, got {kl_warmup_epochs!r}")
        if isinstance(image_shift, bool) or not (isinstance(image_shift, int) and image_shift >= 0):
            raise UsageError(
                f"image_shift must be a whole number of pixels >= 0, got {image_shift!r}"
            )

    @property
    def family(self) -> str:
        return self.model.family

    def forward(self, batch: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        return self.model.elbo(batch)

    def on_train_start(self) -> None:
        # A resumed run gets its scheduler back from the checkpoint, with the step count it was
        # planned for; a larger budget would step a one-cycle schedule past its end.
        for config in self.trainer.lr_scheduler_configs:
            planned = getattr(config.scheduler, "total_steps", None)
            wanted = int(self.trainer.estimated_stepping_batches)
            if planned is not None and planned < wanted:
                raise UsageError(
                    f"this run's learning-rate schedule spans {planned} steps, the resumed run "
                    f"asks for {wanted}: a schedule cannot be stretched; start a new run (or "
                    f"keep the original max_epochs / limit_train_batches)"
                )

    def on_train_batch_start(self, batch: Any, batch_idx: int) -> None:
        """Set ``kl_scale`` (MUSE, MVAE) to the fraction of the warm-up done at this step.

        The warm-up counts optimizer steps, ``kl_warmup_epochs`` times the batches of an
        epoch, so short runs (the demo's 300-batch epochs) warm up as smoothly as long ones.
        """
        warmup = self.hparams.kl_warmup_epochs
        if hasattr(self.model, "kl_scale"):
            steps = warmup * max(1, int(self.trainer.num_training_batches))
            self.model.kl_scale = min(1.0, (self.global_step + 1) / steps) if warmup else 1.0

    def _step(
        self,
        batch: dict[str, torch.Tensor],
        split: str,
        inputs: dict[str, torch.Tensor] | None = None,
    ) -> torch.Tensor:
        # Terms are summed here and logged once per epoch (_log_epoch): Lightning's per-call
        # logging cost about 10 % of a small model's step (benchmarks/bench_train.py).
        terms = self.model.elbo(batch, inputs)
        size = len(next(iter(batch.values())))
        sums = self._sums.setdefault(split, {})
        for key, value in terms.items():
            sums[key] = sums.get(key, 0.0) + value.detach() * size
        self._counts[split] = self._counts.get(split, 0) + size
        return terms["loss"]

    def _log_epoch(self, split: str) -> None:
        sums, count = self._sums.pop(split, {}), self._counts.pop(split, 0)
        if count:  # sync_dist: the mean over DDP ranks (equal shards); a no-op on one process
            means = {f"{split}/{k}": v / count for k, v in sums.items() if k != "loss"}
            self.log_dict(means, sync_dist=True)
            self.log(f"{split}/loss", sums["loss"] / count, prog_bar=True, sync_dist=True)

    def on_train_epoch_end(self) -> None:
        self._log_epoch("train")

    def on_validation_epoch_end(self) -> None:
        self._log_epoch("val")

    def on_test_epoch_end(self) -> None:
        self._log_epoch("test")

    def on_save_checkpoint(self, checkpoint: dict[str, Any]) -> None:
        if hasattr(self.model, "kl_scale"):  # a plain attribute, not in the state dict
            checkpoint["kl_scale"] = float(self.model.kl_scale)
        # the training writers' original letters: the hands a generated word is written in
        # (prg.pipeline.hands), so a checkpoint writes without its dataset
        datamodule = getattr(self._trainer, "datamodule", None) if self._trainer else None
        letters = getattr(datamodule, "train_letters", None)
        if letters is not None:
            from prg.data.hands import CHECKPOINT_KEY, HandBank

            checkpoint[CHECKPOINT_KEY] = HandBank.from_split(letters).to_checkpoint()

    def on_load_checkpoint(self, checkpoint: dict[str, Any]) -> None:
        if hasattr(self.model, "kl_scale") and "kl_scale" in checkpoint:
            self.model.kl_scale = checkpoint["kl_scale"]

    def training_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> torch.Tensor:
        shift = self.hparams.get("image_shift", 0)  # absent from checkpoints saved before it
        if shift and "image" in batch:
            inputs = {**batch, "image": shift_images(batch["image"], shift)}
            return self._step(batch, "train", inputs)
        return self._step(batch, "train")

    def validation_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> None:
        self._step(batch, "val")

    def test_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> None:
        self._step(batch, "test")

    def configure_optimizers(self) -> torch.optim.Optimizer | dict[str, Any]:
        optimizer = instantiate(self.hparams.optimizer)(params=self.parameters())
        if not self.hparams.scheduler:
            return optimizer
        total = int(self.trainer.estimated_stepping_batches)
        scheduler = instantiate(self.hparams.scheduler)(optimizer, total_steps=total)
        return {
            "optimizer": optimizer,
            "lr_scheduler": {"scheduler": scheduler, "interval": "step", "frequency": 1},
        }
