"""MoPoE (Sutter et al. 2021): the posterior a mixture over subsets of products of experts.

Each modality m has an expert q_m(z | x_m) (the appendix encoder, latent 16) and a decoder
p(x_m | z). For a non-empty subset S the subset posterior is the product of its experts,
``q_S(z) ∝ prod_{m in S} q_m(z | x_m)`` (no prior expert: Sutter et al., eq. 9), and the
posterior from the given modalities G is the uniform mixture over the non-empty subsets S of
G, ``q(z | x_G) = (1/(2^|G| - 1)) sum_{S ⊆ G} q_S(z)`` (:class:`~prg.models.mixture.Mixture`;
one given modality: its expert).

Loss per sample i, averaged over the batch (the objective of Sutter et al., eq. 10, as their
code estimates it)::

    sum_m lambda_m (-log p(x_m | z_i)) + beta (1/|P|) sum_{S in P} KL(q_S(z | x_S) || N(0, I))

with P the 2^M - 1 non-empty subsets of all M modalities and ``z_i ~ q_{S_i}`` drawn from one
subset posterior per sample: the subsets are dealt to the batch's rows in turn from a random
offset, so each gets ``|B| / |P|`` rows (stratified sampling of the mixture). The KL of the mixture
is replaced by the mean of its components' KLs, an upper bound (KL is convex). Written for any
number of modalities >= 2.
"""

from __future__ import annotations

import torch
from torch import nn

from prg.models.base import Gaussian, ImportancePath, Inputs, MultimodalVAE
from prg.models.fusion import kl_standard_normal, product_of_experts, reparameterise
from prg.models.mixture import Mixture, mixture_of, nonempty_subsets
from prg.models.modalities import MODALITIES
from prg.models.mvae import modality_weights


def stratified_assignment(batch: int, n_subsets: int, offset: int) -> torch.Tensor:
    """Subset index per row: ``(row + offset) mod n_subsets``, shape (batch,).

    Examples
    --------
    >>> stratified_assignment(5, 3, 1).tolist()
    [1, 2, 0, 1, 2]
    """
    return (torch.arange(batch) + offset) % n_subsets


class MoPoE(MultimodalVAE):
    """Multimodal VAE with a mixture-of-products-of-experts posterior (Sutter et al. 2021).

    Parameters
    ----------
    modalities : tuple of str
        At least two of :data:`~prg.models.modalities.MODALITIES`.
    latent_dim : int
        Size of the one latent (16).
    traj_std : float
        Std of the trajectory's Gaussian likelihood.
    weights : dict, optional
        Reconstruction weight lambda_m per modality (default
        :data:`prg.models.mvae.DEFAULT_WEIGHTS`).
    beta : float
        Weight of the KL term.
    """

    family = "mopoe"
    mixture_posterior = True

    def __init__(
        self,
        modalities: tuple[str, ...] = ("traj", "label", "image"),
        latent_dim: int = 16,
        traj_std: float = 0.1,
        weights: dict[str, float] | None = None,
        beta: float = 1.0,
    ):
        super().__init__(tuple(modalities), latent_dim, traj_std)
        if len(self.modalities) < 2:
            raise ValueError("a MoPoE needs at least two modalities")
        self.weights = modality_weights(self.modalities, weights)
        self.beta = float(beta)
        self.subsets = nonempty_subsets(self.modalities)
        self.experts = nn.ModuleDict(
            {m: MODALITIES[m].encoder(latent_dim) for m in self.modalities}
        )
        self.decoders = nn.ModuleDict(
            {m: MODALITIES[m].decoder(latent_dim) for m in self.modalities}
        )

    def noise(self, like: torch.Tensor) -> torch.Tensor:
        """Standard normal noise of one reparameterised sample (a seam for tests)."""
        return torch.randn_like(like)

    def offset(self) -> int:
        """The first row's subset index in this batch's stratified assignment (a seam for
        tests)."""
        return int(torch.randint(len(self.subsets), ()))

    @staticmethod
    def subset_posterior(experts: list[tuple[torch.Tensor, torch.Tensor]]) -> Gaussian:
        """q_S: the product of the experts of S, without the prior expert."""
        return Gaussian(
            *product_of_experts([e[0] for e in experts], [e[1] for e in experts], False)
        )

    def encode(self, inputs: Inputs) -> Gaussian | Mixture:
        """q(z | x_G): the mixture over the non-empty subsets of the given G of their
        products of experts (one given modality: its expert)."""
        self.check_inputs(inputs)
        given = {m: self.experts[m](inputs[m]) for m in self.modalities if m in inputs}
        return mixture_of(
            [self.subset_posterior([given[m] for m in s]) for s in nonempty_subsets(tuple(given))]
        )

    def decode(self, z: torch.Tensor, modality: str, inputs: Inputs | None = None) -> torch.Tensor:
        return self.decoders[modality](z)

    def elbo(self, batch: Inputs, inputs: Inputs | None = None) -> dict[str, torch.Tensor]:
        inputs = batch if inputs is None else inputs
        experts = {m: self.experts[m](inputs[m]) for m in self.modalities}
        posteriors = [self.subset_posterior([experts[m] for m in s]) for s in self.subsets]
        mus = torch.stack([q.mu for q in posteriors])  # (|P|, B, d)
        logvars = torch.stack([q.logvar for q in posteriors])
        rows = torch.arange(mus.shape[1], device=mus.device)
        pick = stratified_assignment(mus.shape[1], len(self.subsets), self.offset()).to(mus.device)
        mu, logvar = mus[pick, rows], logvars[pick, rows]
        z = reparameterise(mu, logvar, self.noise(mu))
        terms: dict[str, torch.Tensor] = {}
        loss = 0.0
        for m in self.modalities:
            rec = -self.likelihoods.log_prob(m, self.decoders[m](z), batch[m]).mean()
            terms[f"rec_{m}"] = rec
            loss = loss + self.weights[m] * rec
        terms["kl"] = kl_standard_normal(mus, logvars).mean(0).mean()
        terms["loss"] = loss + self.beta * terms["kl"]
        return terms

    def importance_path(self, target: str, x_target: torch.Tensor, given: Inputs) -> ImportancePath:
        """Marginal log p(x_m) (``given`` empty): proposal q_m(z | x_m), the subset {m};
        conditional log p(x_a | x_S): proposal q(z | x_S), the mixture over S's subsets (its
        density the mean of theirs). Decoder p(x_a | z)."""
        self.check_cell(target, given)
        proposal = self.encode(given or {target: x_target})
        return ImportancePath(proposal, self.decoders[target], target, self.latent_dim)
