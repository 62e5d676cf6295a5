"""AVAE (Yin et al. 2017): one VAE per modality, latent spaces associated by a symmetric KL.

Written for any pair (or more) of modalities; ``avae_ts`` and ``avae_ti`` just pick the pair.
Loss per sample, averaged over the batch (the reference code sums some terms over the batch —
a quirk not kept): ``sum_m w_m [Rec_m + KL(q_m || N(0, I))] + alpha * sum_{i<j} SKL(q_i, q_j)``.
As in the reference code, one epsilon per batch row is shared by the modalities
(``z_m = mu_m + sigma_m * eps``). Cross-modal generation encodes the one given modality to its
posterior and decodes with the target's decoder.
"""

from __future__ import annotations

from itertools import combinations

import torch
from torch import nn

from prg.models.base import Gaussian, ImportancePath, Inputs, MultimodalVAE
from prg.models.fusion import kl_standard_normal, reparameterise, symmetric_kl
from prg.models.modalities import MODALITIES


class AVAE(MultimodalVAE):
    family = "avae"

    def __init__(
        self,
        modalities: tuple[str, ...] = ("traj", "label"),
        latent_dim: int = 16,
        traj_std: float = 0.1,
        alpha: float = 1.0,
        weights: dict[str, float] | None = None,
    ):
        super().__init__(tuple(modalities), latent_dim, traj_std)
        if len(self.modalities) < 2:
            raise ValueError("an AVAE needs at least two modalities")
        # avae_ts, avae_ti: the paper's letters of its modalities
        self.family = "avae_" + "".join(MODALITIES[m].letter.lower() for m in self.modalities)
        self.alpha = alpha
        self.weights = {m: float((weights or {}).get(m, 1.0)) for m in self.modalities}
        self.encoders = nn.ModuleDict(
            {m: MODALITIES[m].encoder(latent_dim) for m in self.modalities}
        )
        self.decoders = nn.ModuleDict(
            {m: MODALITIES[m].decoder(latent_dim) for m in self.modalities}
        )

    @property
    def accepted_inputs(self) -> list[tuple[str, ...]]:
        return [(m,) for m in self.modalities]

    def encode(self, inputs: Inputs) -> Gaussian:
        """q_m(z | x_m) of the single given modality."""
        self.check_inputs(inputs)
        (modality,) = [m for m in self.modalities if m in inputs]
        return Gaussian(*self.encoders[modality](inputs[modality]))

    def decode(self, z: torch.Tensor, modality: str, inputs: Inputs | None = None) -> torch.Tensor:
        return self.decoders[modality](z)

    def elbo(self, batch: Inputs, inputs: Inputs | None = None) -> dict[str, torch.Tensor]:
        inputs = batch if inputs is None else inputs
        posts = {m: Gaussian(*self.encoders[m](inputs[m])) for m in self.modalities}
        eps = torch.randn_like(posts[self.modalities[0]].mu)
        terms: dict[str, torch.Tensor] = {}
        loss = 0.0
        for m, q in posts.items():
            z = reparameterise(q.mu, q.logvar, eps)
            rec = -self.likelihoods.log_prob(m, self.decoders[m](z), batch[m]).mean()
            kl = kl_standard_normal(q.mu, q.logvar).mean()
            terms[f"rec_{m}"], terms[f"kl_{m}"] = rec, kl
            loss = loss + self.weights[m] * (rec + kl)
        skl = sum(
            symmetric_kl(posts[a].mu, posts[a].logvar, posts[b].mu, posts[b].logvar).mean()
            for a, b in combinations(self.modalities, 2)
        )
        terms["skl"] = skl
        terms["loss"] = loss + self.alpha * skl
        return terms

    def importance_path(self, target: str, x_target: torch.Tensor, given: Inputs) -> ImportancePath:
        """Marginal (``given`` empty): proposal q_target(z | x_target); conditional (one given
        modality b): proposal q_b(z | x_b). Either way decoded by the target's decoder."""
        self.check_cell(target, given)
        proposal = self.encode(given or {target: x_target})
        return ImportancePath(proposal, self.decoders[target], target, self.latent_dim)
