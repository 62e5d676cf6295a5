"""CVAE(T | S), the paper's baseline: a trajectory VAE conditioned on the label.

Encoder q(z | x_T, y) on concat(x_T, onehot(y)); decoder p(x_T | z, y) on concat(z, onehot(y));
prior N(0, I). Loss: reconstruction + KL. Generation from a label: z from the prior (its mean 0
with ``temperature=0``), decoded with the label.

Optional, not in the paper (``mode_seeking`` > 0, :meth:`CVAE._mode_seeking`): the prior mean
decoded with a label must also reconstruct the nearest of the last ``mode_bank`` training
trajectories of that class, so that it writes one real style of its letter, not a blend.
"""

from __future__ import annotations

from typing import ClassVar

import torch
import torch.nn.functional as F

from prg.alphabet import NUM_CLASSES
from prg.models.base import Gaussian, ImportancePath, Inputs, MultimodalVAE
from prg.models.components import (
    TRAJ_DIM,
    ClassRing,
    TrajectoryDecoder,
    TrajectoryEncoder,
    nearest_same_class,
)
from prg.models.fusion import kl_standard_normal, reparameterise


class CVAE(MultimodalVAE):
    family = "cvae"

    def __init__(
        self,
        latent_dim: int = 16,
        traj_std: float = 0.1,
        kl_weight: float = 1.0,
        mode_seeking: float = 0.0,
        mode_bank: int = 0,
    ):
        super().__init__(("traj", "label"), latent_dim, traj_std)
        self.kl_weight, self.mode_seeking, self.mode_bank = kl_weight, mode_seeking, int(mode_bank)
        self.encoder = TrajectoryEncoder(latent_dim, extra_inputs=NUM_CLASSES)
        self.decoder = TrajectoryDecoder(latent_dim, extra_inputs=NUM_CLASSES)
        if mode_seeking and self.mode_bank:
            self.bank = ClassRing(NUM_CLASSES, self.mode_bank, TRAJ_DIM)

    accepted_inputs: ClassVar[list[tuple[str, ...]]] = [("traj", "label"), ("label",)]
    generated_modalities: ClassVar[tuple[str, ...]] = ("traj",)

    @staticmethod
    def _onehot(label: torch.Tensor) -> torch.Tensor:
        return F.one_hot(label, NUM_CLASSES).float()

    def encode(self, inputs: Inputs) -> Gaussian:
        """q(z | x_T, y) from both; the prior N(0, I) from the label alone (the map psi_S)."""
        self.check_inputs(inputs)
        label = inputs["label"]
        if "traj" in inputs:
            return Gaussian(*self.encoder(torch.cat([inputs["traj"], self._onehot(label)], -1)))
        zeros = torch.zeros(len(label), self.latent_dim, device=label.device)
        return Gaussian(zeros, zeros.clone())

    def decode(self, z: torch.Tensor, modality: str, inputs: Inputs | None = None) -> torch.Tensor:
        if modality != "traj" or not inputs or "label" not in inputs:
            raise ValueError("the CVAE decodes trajectories only, given the label in `inputs`")
        return self.decoder(torch.cat([z, self._onehot(inputs["label"])], -1))

    def elbo(self, batch: Inputs, inputs: Inputs | None = None) -> dict[str, torch.Tensor]:
        inputs = batch if inputs is None else inputs
        posterior = self.encode({"traj": inputs["traj"], "label": batch["label"]})
        z = reparameterise(posterior.mu, posterior.logvar)
        rec = -self.likelihoods.log_prob("traj", self.decode(z, "traj", batch), batch["traj"])
        kl = kl_standard_normal(posterior.mu, posterior.logvar)
        terms = {"rec_traj": rec.mean(), "kl": kl.mean()}
        terms["loss"] = terms["rec_traj"] + self.kl_weight * terms["kl"]
        terms["elbo"] = -(terms["rec_traj"] + terms["kl"])
        if self.mode_seeking:
            terms["mode_traj"] = self._mode_seeking(batch)
            terms["loss"] = terms["loss"] + self.mode_seeking * terms["mode_traj"]
        return terms

    def _mode_seeking(self, batch: Inputs) -> torch.Tensor:
        """The reconstruction loss (the squared error over 2 traj_std^2, as in ``rec_traj``) of
        the nearest trajectory of each sample's class, from the prior mean decoded with its
        label. The candidates are the batch's samples of that class or, with ``mode_bank`` >
        0, the last ``mode_bank`` of that class seen in training, this batch's among them.

        Decoded from z = 0 a label gives the decoder's average over its class's styles, and a
        blend of styles can read as another letter; the nearest real trajectory is the style
        closest to what the decoder already writes, so the decoder bends least."""
        traj, labels = batch["traj"], batch["label"]
        decoded = self.decode(
            torch.zeros(len(labels), self.latent_dim, device=traj.device), "traj", batch
        )
        if self.mode_bank:
            if self.training:  # validation never changes what training aims at
                self.bank.store(traj, labels)
            nearest = self.bank.nearest_distance(decoded, labels)
        else:
            nearest = nearest_same_class(decoded, traj, labels)
        return (nearest / (2 * self.likelihoods.traj_std**2)).mean()

    likelihood_cells: ClassVar[list[tuple[str, tuple[str, ...]]]] = [("traj", ("label",))]

    def importance_path(self, target: str, x_target: torch.Tensor, given: Inputs) -> ImportancePath:
        """log p(x_T | y): proposal q(z | x_T, y), decoder with y (as the reference code)."""
        self.check_cell(target, given)
        inputs = {"traj": x_target, "label": given["label"]}
        return ImportancePath(
            self.encode(inputs),
            lambda z: self.decode(z, "traj", _repeat(given, z)),
            "traj",
            self.latent_dim,
        )


def _repeat(inputs: Inputs, z: torch.Tensor) -> Inputs:
    """Tile inputs (B, ...) to match latents (K*B, d) laid out as K blocks of B."""
    k = z.shape[0] // len(next(iter(inputs.values())))
    return {m: v.repeat(k, *([1] * (v.dim() - 1))) for m, v in inputs.items()}
