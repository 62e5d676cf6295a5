"""MMVAE (Shi et al. 2019): one latent, the posterior a mixture of the unimodal experts.

Each modality m has an expert q_m(z | x_m) (the appendix encoder, latent 16) and a decoder
p(x_m | z). The posterior from a subset S is the uniform mixture of its experts,
``q(z | x_S) = (1/|S|) sum_{m in S} q_m(z | x_m)`` (:class:`~prg.models.mixture.Mixture`).
Shi et al. use Laplace posteriors and priors; here every distribution is a diagonal Gaussian
and the prior N(0, I), as in the project's other families, so the encoders, the importance
estimator and the generation modes are shared.

Loss per sample, averaged over the batch: minus the stratified importance-weighted bound of Shi
et al. (eq. 4), with K samples from each component::

    L = (1/M) sum_m log (1/K) sum_k w_{m,k},   z_{m,k} ~ q_m(z | x_m)
    log w = log N(z; 0, I) + sum_n lambda_n log p(x_n | z) - log q(z | x_{1..M})

each sample decoded into every modality and weighed against the whole mixture. With
``dreg=True`` the gradient is the doubly reparameterised one (DReG, Tucker et al. 2019, as Shi
et al. train): the encoders' gradient through each z carries the normalised weight squared,
the mixture's own density is taken with its parameters held, and the decoders' gradient is the
IWAE one; the reported loss keeps the value of -L. Written for any number of modalities >= 2.
"""

from __future__ import annotations

import torch
from torch import nn

from prg.models.base import Gaussian, ImportancePath, Inputs, MultimodalVAE
from prg.models.fusion import reparameterise
from prg.models.mixture import Mixture, log_mean_exp, mixture_of
from prg.models.modalities import MODALITIES
from prg.models.mvae import modality_weights


def standard_normal_log_prob(z: torch.Tensor) -> torch.Tensor:
    """log N(z; 0, I), summed over the last dimension."""
    return Gaussian(torch.zeros_like(z), torch.zeros_like(z)).log_prob(z)


class MMVAE(MultimodalVAE):
    """Multimodal VAE with a mixture-of-experts posterior (Shi et al. 2019), Gaussian.

    Parameters
    ----------
    modalities : tuple of str
        At least two of :data:`~prg.models.modalities.MODALITIES`.
    latent_dim : int
        Size of the one latent (16).
    traj_std : float
        Std of the trajectory's Gaussian likelihood.
    weights : dict, optional
        Likelihood scaling lambda_m per modality (default
        :data:`prg.models.mvae.DEFAULT_WEIGHTS`).
    k : int
        Importance samples per component and training sample.
    dreg : bool
        Train with the DReG gradient estimator.
    """

    family = "mmvae"
    mixture_posterior = True

    def __init__(
        self,
        modalities: tuple[str, ...] = ("traj", "label", "image"),
        latent_dim: int = 16,
        traj_std: float = 0.1,
        weights: dict[str, float] | None = None,
        k: int = 1,
        dreg: bool = False,
    ):
        super().__init__(tuple(modalities), latent_dim, traj_std)
        if len(self.modalities) < 2:
            raise ValueError("an MMVAE needs at least two modalities")
        if isinstance(k, bool) or not isinstance(k, int) or k < 1:
            raise ValueError(f"k must be an integer >= 1, got {k!r}")
        self.weights = modality_weights(self.modalities, weights)
        self.k, self.dreg = k, bool(dreg)
        self.experts = nn.ModuleDict(
            {m: MODALITIES[m].encoder(latent_dim) for m in self.modalities}
        )
        self.decoders = nn.ModuleDict(
            {m: MODALITIES[m].decoder(latent_dim) for m in self.modalities}
        )

    def noise(self, like: torch.Tensor, k: int) -> torch.Tensor:
        """Standard normal noise of ``k`` reparameterised samples, shape ``(k, *like.shape)`` (a
        seam for tests)."""
        return torch.randn((k, *like.shape), device=like.device, dtype=like.dtype)

    def encode(self, inputs: Inputs) -> Gaussian | Mixture:
        """q(z | x_S): the uniform mixture of the experts of S (one expert: itself)."""
        self.check_inputs(inputs)
        return mixture_of(
            [Gaussian(*self.experts[m](inputs[m])) for m in self.modalities if m in inputs]
        )

    def decode(self, z: torch.Tensor, modality: str, inputs: Inputs | None = None) -> torch.Tensor:
        return self.decoders[modality](z)

    def _log_likelihood(self, z: torch.Tensor, batch: Inputs) -> torch.Tensor:
        """sum_n lambda_n log p(x_n | z) for z of shape (K, B, d); returns (K, B)."""
        k, b = z.shape[:2]
        total = 0.0
        for m in self.modalities:
            params = self.decoders[m](z.reshape(k * b, -1))
            params = params.reshape(k, b, *params.shape[1:])
            total = total + self.weights[m] * self.likelihoods.log_prob(m, params, batch[m])
        return total

    def elbo(self, batch: Inputs, inputs: Inputs | None = None) -> dict[str, torch.Tensor]:
        inputs = batch if inputs is None else inputs
        experts = {m: Gaussian(*self.experts[m](inputs[m])) for m in self.modalities}
        # DReG: the mixture's density with its parameters held (the gradient reaches the
        # encoders through the samples only)
        held = (
            Mixture([Gaussian(q.mu.detach(), q.logvar.detach()) for q in experts.values()])
            if self.dreg
            else Mixture(list(experts.values()))
        )
        terms: dict[str, torch.Tensor] = {}
        bound, surrogate = 0.0, 0.0
        for m, q in experts.items():
            z = reparameterise(q.mu, q.logvar, self.noise(q.mu, self.k))  # (K, B, d)
            log_w = standard_normal_log_prob(z) + self._log_likelihood(z, batch) - held.log_prob(z)
            component = log_mean_exp(log_w, 0)  # (B,)
            terms[f"iwae_{m}"] = component.mean()
            bound = bound + component / len(experts)
            if self.dreg and z.requires_grad:
                normalised = torch.softmax(log_w, 0).detach()  # (K, B)
                z.register_hook(lambda grad, w=normalised: grad * w[..., None].to(grad.dtype))
                surrogate = surrogate + (normalised * log_w).sum(0) / len(experts)
        loss = -bound.mean()
        if self.dreg and torch.is_tensor(surrogate):  # the value of -L, DReG's gradient
            loss = loss.detach() - surrogate.mean() + surrogate.mean().detach()
        terms["loss"] = loss
        return terms

    def importance_path(self, target: str, x_target: torch.Tensor, given: Inputs) -> ImportancePath:
        """Marginal log p(x_m) (``given`` empty): proposal q_m(z | x_m), m's own component;
        conditional log p(x_a | x_S): proposal q(z | x_S), the mixture of S's experts (its
        density the mean of theirs). Decoder p(x_a | z)."""
        self.check_cell(target, given)
        proposal = self.encode(given or {target: x_target})
        return ImportancePath(proposal, self.decoders[target], target, self.latent_dim)
