"""MVAE (Wu & Goodman 2018): one latent, the posterior of any subset a product of experts.

Each modality m has an expert q_m(z | x_m) (the appendix encoder, latent 16) and a decoder
p(x_m | z). The posterior from a subset S is the product of the experts of S **and the prior
expert N(0, I)** (:func:`~prg.models.fusion.product_of_experts`):
``q(z | x_S) ∝ N(0, I) prod_{m in S} q_m(z | x_m)``, precision ``1 + sum_m 1/var_m``.

Loss per sample, averaged over the batch (the subsampled objective of Wu & Goodman, sec. 3)::

    sum over the subsets S in {all} ∪ {each single modality} ∪ {J random subsets}:
        -ELBO_S = sum_{m in S} lambda_m (-log p(x_m | z_S)) + beta KL(q(z | x_S) || N(0, I))

with one reparameterised ``z_S ~ q(z | x_S)`` per term; each term reconstructs the modalities
of its own subset only. The KL terms are multiplied by ``kl_scale`` (1 outside training), which
the training loop can ramp up from 0 (Wu & Goodman anneal it the same way): at full weight from
the first step, an image-only term is minimised by an image expert that says nothing, and one
driven to a huge variance in the first 50 steps never recovered (its gradients vanish; measured:
every cell given the image at chance, 1/62). The J random subsets (``random_subsets``) are drawn per batch, uniformly
among the subsets neither joint nor single (for 3 modalities, the pairs); with 2 modalities there
are none. Written for any number of modalities >= 2.
"""

from __future__ import annotations

import torch
from torch import nn

from prg.models.base import Gaussian, ImportancePath, Inputs, MultimodalVAE
from prg.models.fusion import kl_standard_normal, product_of_experts, reparameterise
from prg.models.mixture import nonempty_subsets
from prg.models.modalities import LETTER, MODALITIES

#: The per-modality reconstruction weights of MUSE's config (the label's 50 balances its one
#: categorical value against the trajectory's 200 and the image's 784 values; Wu & Goodman weigh
#: MNIST's label by 50 too).
DEFAULT_WEIGHTS = {"traj": 1.0, "label": 50.0, "image": 1.0}


def subset_name(subset: tuple[str, ...]) -> str:
    """``TSI``-style letters of a subset (the paper's letters)."""
    return "".join(LETTER.get(m, m) for m in subset)


def modality_weights(modalities: tuple[str, ...], given: dict[str, float] | None) -> dict:
    """``given`` completed by :data:`DEFAULT_WEIGHTS` (1 for a modality without one)."""
    return {m: float((given or {}).get(m, DEFAULT_WEIGHTS.get(m, 1.0))) for m in modalities}


class MVAE(MultimodalVAE):
    """Multimodal VAE with a product-of-experts posterior (Wu & Goodman 2018).

    Parameters
    ----------
    modalities : tuple of str
        At least two of :data:`~prg.models.modalities.MODALITIES`.
    latent_dim : int
        Size of the one latent (16, the appendix networks').
    traj_std : float
        Std of the trajectory's Gaussian likelihood.
    weights : dict, optional
        Reconstruction weight lambda_m per modality (default :data:`DEFAULT_WEIGHTS`).
    beta : float
        Weight of every KL term.
    random_subsets : int
        J, the random subsets whose ELBOs join the joint and single ones in each batch.
    max_expert_logvar : float, optional
        A smooth upper bound on each expert's log-variance in the product
        (``b - softplus(b - logvar)``): an expert never says less than N(0, e^b), so the
        product cannot ignore it. None: no bound (Wu & Goodman).
    """

    family = "mvae"

    def __init__(
        self,
        modalities: tuple[str, ...] = ("traj", "label", "image"),
        latent_dim: int = 16,
        traj_std: float = 0.1,
        weights: dict[str, float] | None = None,
        beta: float = 1.0,
        random_subsets: int = 0,
        max_expert_logvar: float | None = None,
    ):
        super().__init__(tuple(modalities), latent_dim, traj_std)
        if len(self.modalities) < 2:
            raise ValueError("an MVAE needs at least two modalities")
        if isinstance(random_subsets, bool) or not isinstance(random_subsets, int):
            raise ValueError(f"random_subsets must be an integer >= 0, got {random_subsets!r}")
        if random_subsets < 0:
            raise ValueError(f"random_subsets must be an integer >= 0, got {random_subsets!r}")
        self.weights = modality_weights(self.modalities, weights)
        self.beta, self.random_subsets = float(beta), random_subsets
        self.kl_scale = 1.0  # the training loop's warm-up of the KL terms
        self.max_expert_logvar = None if max_expert_logvar is None else float(max_expert_logvar)
        self.experts = nn.ModuleDict(
            {m: MODALITIES[m].encoder(latent_dim) for m in self.modalities}
        )
        self.decoders = nn.ModuleDict(
            {m: MODALITIES[m].decoder(latent_dim) for m in self.modalities}
        )

    def noise(self, like: torch.Tensor) -> torch.Tensor:
        """The standard normal noise of one reparameterised sample (a seam for tests)."""
        return torch.randn_like(like)

    def posterior(self, experts: dict[str, tuple[torch.Tensor, torch.Tensor]]) -> Gaussian:
        """q(z | x_S): the product of the given experts' Gaussians and N(0, I)."""
        logvars = [e[1] for e in experts.values()]
        if self.max_expert_logvar is not None:
            bound = self.max_expert_logvar
            logvars = [bound - nn.functional.softplus(bound - lv) for lv in logvars]
        return Gaussian(*product_of_experts([e[0] for e in experts.values()], logvars))

    def encode(self, inputs: Inputs) -> Gaussian:
        """q(z | x_S) for any non-empty subset S."""
        self.check_inputs(inputs)
        return self.posterior(
            {m: self.experts[m](inputs[m]) for m in self.modalities if m in inputs}
        )

    def decode(self, z: torch.Tensor, modality: str, inputs: Inputs | None = None) -> torch.Tensor:
        return self.decoders[modality](z)

    def training_subsets(self) -> list[tuple[str, ...]]:
        """The subsets of this batch's ELBO terms: the joint, each single modality, and
        ``random_subsets`` drawn (with replacement) among the others."""
        middle = [s for s in nonempty_subsets(self.modalities) if 1 < len(s) < len(self.modalities)]
        chosen = []
        if middle and self.random_subsets:
            picks = torch.randint(len(middle), (self.random_subsets,)).tolist()
            chosen = [middle[i] for i in picks]
        return [self.modalities] + [(m,) for m in self.modalities] + chosen

    def elbo(self, batch: Inputs, inputs: Inputs | None = None) -> dict[str, torch.Tensor]:
        inputs = batch if inputs is None else inputs
        experts = {m: self.experts[m](inputs[m]) for m in self.modalities}  # each computed once
        terms: dict[str, torch.Tensor] = {}
        loss = 0.0
        subsets = self.training_subsets()
        fixed = len(self.modalities) + 1  # the joint and the single ones; the random ones after
        for i, subset in enumerate(subsets):
            q = self.posterior({m: experts[m] for m in subset})
            z = reparameterise(q.mu, q.logvar, self.noise(q.mu))
            kl = kl_standard_normal(q.mu, q.logvar)
            nelbo = self.beta * self.kl_scale * kl
            for m in subset:
                rec = -self.likelihoods.log_prob(m, self.decoders[m](z), batch[m])
                nelbo = nelbo + self.weights[m] * rec
                if subset == self.modalities:
                    terms[f"rec_{m}"] = rec.mean()
            if subset == self.modalities:
                terms["kl"] = kl.mean()
            # the random subsets change from batch to batch: logged as one sum
            name = f"nelbo_{subset_name(subset)}" if i < fixed else "nelbo_random"
            terms[name] = terms.get(name, 0.0) + nelbo.mean()
            loss = loss + nelbo.mean()
        terms["loss"] = loss
        return terms

    def importance_path(self, target: str, x_target: torch.Tensor, given: Inputs) -> ImportancePath:
        """Marginal log p(x_m) (``given`` empty): proposal q(z | x_m), the product of m's expert
        and the prior; conditional log p(x_a | x_S): proposal q(z | x_S). Decoder p(x_a | z)."""
        self.check_cell(target, given)
        proposal = self.encode(given or {target: x_target})
        return ImportancePath(proposal, self.decoders[target], target, self.latent_dim)
