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
    beta_warmup_epochs : int
        Linear warm-up of MUSE's top-level KL weight over this many epochs (0: none).
    """

    def __init__(
        self, model: dict[str, Any], optimizer: dict[str, Any], beta_warmup_epochs: int = 0
    ):
        super().__init__()
        model, optimizer = _plain(model), _plain(optimizer)  # checkpoints hold plain containers
        self.save_hyperparameters(
            {"model": model, "optimizer": optimizer, "beta_warmup_epochs": beta_warmup_epochs}
        )
        self.model: MultimodalVAE = instantiate(model, _convert_="all")
        self._sums: dict[str, dict[str, torch.Tensor]] = {}
        self._counts: dict[str, int] = {}
        if beta_warmup_epochs < 0:
            raise UsageError(f"beta_warmup_epochs must be >= 0, got {beta_warmup_epochs}")

    @property
    def family(self) -> str:
        return self.model.family

    def forward(self, batch: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        return self.model.elbo(batch)

    def on_train_epoch_start(self) -> None:
        warmup = self.hparams.beta_warmup_epochs
        if hasattr(self.model, "beta_scale"):
            self.model.beta_scale = min(1.0, (self.current_epoch + 1) / warmup) if warmup else 1.0

    def _step(self, batch: dict[str, torch.Tensor], split: str) -> torch.Tensor:
        # Terms are summed here and logged once per epoch (_log_epoch): Lightning's per-call
        # logging cost about 10 % of a small model's step (benchmarks/bench_train.py).
        terms = self.model.elbo(batch)
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
        if hasattr(self.model, "beta_scale"):  # a plain attribute, not in the state dict
            checkpoint["beta_scale"] = float(self.model.beta_scale)

    def on_load_checkpoint(self, checkpoint: dict[str, Any]) -> None:
        if hasattr(self.model, "beta_scale") and "beta_scale" in checkpoint:
            self.model.beta_scale = checkpoint["beta_scale"]

    def training_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> torch.Tensor:
        return self._step(batch, "train")

    def validation_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> None:
        self._step(batch, "val")

    def test_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> None:
        self._step(batch, "test")

    def configure_optimizers(self) -> torch.optim.Optimizer:
        return instantiate(self.hparams.optimizer)(params=self.parameters())
