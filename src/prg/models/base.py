"""One interface for every multimodal VAE family (CVAE, AVAE, MUSE; MVAE, MMVAE, MoPoE).

Batches and inputs are dicts keyed by modality (:data:`prg.models.modalities.MODALITIES`: ``traj``
(B, 200), ``label`` (B,) long, ``image`` (B, 1, 28, 28)); a missing modality is simply absent.

- :meth:`MultimodalVAE.encode` — posterior over the family's generative latent from any input
  subset the family supports (a clear :class:`~prg.errors.UsageError` otherwise): a
  :class:`Gaussian`, or for the mixture families a :class:`~prg.models.mixture.Mixture` of them;
- :meth:`MultimodalVAE.decode` — likelihood parameters of a modality from a latent;
- :meth:`MultimodalVAE.generate` — data-space outputs of a target modality from inputs;
- :meth:`MultimodalVAE.elbo` — the training loss and its named terms, averaged over the batch;
- :meth:`MultimodalVAE.importance_path` — what an importance-weighted log-likelihood estimator
  needs for ``log p(x_target | x_given)`` (proposal, prior, decoder), so the estimator is written
  once for all families; :attr:`MultimodalVAE.likelihood_cells` lists the (target, given) pairs a
  family can estimate.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from itertools import combinations

import torch
from torch import nn

from prg.errors import UsageError
from prg.models.fusion import reparameterise
from prg.models.likelihoods import Likelihoods
from prg.models.modalities import LETTER, MODALITIES, NAMES, in_order

__all__ = ["LETTER", "MODALITIES", "Gaussian", "ImportancePath", "Inputs", "MultimodalVAE"]

Inputs = dict[str, torch.Tensor]
_LOG_2PI = math.log(2 * math.pi)


@dataclass
class Gaussian:
    """Diagonal Gaussian given by mean and log-variance, shape (..., d)."""

    mu: torch.Tensor
    logvar: torch.Tensor

    def sample(
        self,
        n: int | None = None,
        temperature: float = 1.0,
        generator: torch.Generator | None = None,
    ) -> torch.Tensor:
        """Reparameterised samples, shape (n, ..., d) (or (..., d) when ``n`` is None), the
        standard deviation scaled by ``temperature``; 0 gives the mean and draws nothing."""
        shape = self.mu.shape if n is None else (n, *self.mu.shape)
        if temperature == 0:
            return self.mu.expand(shape)
        eps = torch.randn(shape, generator=generator, device=self.mu.device, dtype=self.mu.dtype)
        return reparameterise(self.mu, self.logvar, eps * temperature)

    @property
    def mean(self) -> torch.Tensor:
        """E[z], shape (..., d): ``mu`` (the interface a :class:`~prg.models.mixture.Mixture`
        shares)."""
        return self.mu

    def log_prob(self, z: torch.Tensor) -> torch.Tensor:
        """log N(z; mu, var) summed over the last dimension."""
        return -0.5 * ((z - self.mu) ** 2 / self.logvar.exp() + self.logvar + _LOG_2PI).sum(-1)


@dataclass
class ImportancePath:
    """Everything an importance-weighted estimate of ``log p(x_target | x_given)`` needs.

    ``w_k = log p(x_target | decode(z_k)) + prior.log_prob(z_k) - proposal.log_prob(z_k)`` with
    ``z_k ~ proposal``; the estimate is ``logmeanexp_k w_k``. The proposal is a
    :class:`Gaussian` or a :class:`~prg.models.mixture.Mixture` of them (the mixture families):
    anything with ``sample(n, generator=...)`` and ``log_prob``.
    """

    proposal: Gaussian  # or a prg.models.mixture.Mixture
    decode: Callable[[torch.Tensor], torch.Tensor]
    target: str
    latent_dim: int


class MultimodalVAE(nn.Module, ABC):
    """Base class: the modalities a family knows and the interface it implements."""

    family: str = ""

    def __init__(self, modalities: tuple[str, ...], latent_dim: int, traj_std: float = 0.1):
        super().__init__()
        unknown = [m for m in modalities if m not in MODALITIES]
        if unknown:
            raise UsageError(f"unknown modalities {unknown}: accepted are {list(NAMES)}")
        self.modalities = tuple(modalities)
        self.latent_dim = latent_dim
        self.likelihoods = Likelihoods(traj_std=traj_std)

    # ---- interface -----------------------------------------------------------------------
    @abstractmethod
    def encode(self, inputs: Inputs) -> Gaussian:
        """Posterior over the generative latent from the given inputs."""

    @abstractmethod
    def decode(self, z: torch.Tensor, modality: str, inputs: Inputs | None = None) -> torch.Tensor:
        """Likelihood parameters of ``modality`` (``inputs`` carries a CVAE's condition)."""

    @abstractmethod
    def elbo(self, batch: Inputs, inputs: Inputs | None = None) -> dict[str, torch.Tensor]:
        """Loss terms averaged over the batch; ``loss`` is the total to minimise.

        ``inputs``: what the encoders see where it differs from the reconstruction targets in
        ``batch`` (denoising training, e.g. shifted images; default: ``batch`` itself)."""

    @abstractmethod
    def importance_path(self, target: str, x_target: torch.Tensor, given: Inputs) -> ImportancePath:
        """Proposal and decoder for ``log p(x_target | given)``; ``given`` empty: the marginal.

        Raises a :class:`~prg.errors.UsageError` for a pair not in :attr:`likelihood_cells`.
        """

    # ---- shared behaviour ----------------------------------------------------------------
    @property
    def accepted_inputs(self) -> list[tuple[str, ...]]:
        """Input subsets :meth:`encode` accepts (default: every non-empty subset)."""
        return [
            s for r in range(1, len(self.modalities) + 1) for s in combinations(self.modalities, r)
        ]

    @property
    def generated_modalities(self) -> tuple[str, ...]:
        """Modalities :meth:`generate` can produce (default: all it models)."""
        return self.modalities

    @property
    def likelihood_cells(self) -> list[tuple[str, tuple[str, ...]]]:
        """(target, given modalities) pairs :meth:`importance_path` supports (default: every
        marginal, and every target given any accepted subset that leaves the target out)."""
        marginals = [(m, ()) for m in self.modalities]
        conditionals = [(m, s) for m in self.modalities for s in self.accepted_inputs if m not in s]
        return marginals + conditionals

    def check_cell(self, target: str, given: Inputs) -> None:
        """Raise a UsageError unless ``log p(x_target | given)`` is one of this family's cells."""
        cell = (target, in_order(given))
        if cell not in self.likelihood_cells:

            def name(t, g):
                return f"log p(x_{LETTER.get(t, t)}" + (
                    f" | x_{''.join(LETTER.get(m, m) for m in g)})" if g else ")"
                )

            cells = ", ".join(name(*c) for c in self.likelihood_cells)
            raise UsageError(f"{self.family} cannot estimate {name(*cell)}: it estimates {cells}")

    def accepts(self, inputs: Inputs) -> bool:
        return tuple(m for m in self.modalities if m in inputs) in self.accepted_inputs and all(
            m in self.modalities for m in inputs
        )

    def check_inputs(self, inputs: Inputs) -> None:
        """Raise a UsageError naming what was given and what this family accepts."""
        if not self.accepts(inputs):
            given = list(in_order(inputs)) or list(inputs)
            accepted = " or ".join("{" + ", ".join(s) + "}" for s in self.accepted_inputs)
            raise UsageError(
                f"{self.family} cannot encode inputs {{{', '.join(given) or 'nothing'}}}: "
                f"it accepts {accepted}"
            )

    #: Whether :meth:`encode` may return a :class:`~prg.models.mixture.Mixture` (MMVAE,
    #: MoPoE) rather than one Gaussian when several modalities are given.
    mixture_posterior: bool = False

    #: Whether :meth:`encode_imputed` differs from :meth:`encode` (a joint posterior that
    #: imputed modalities can join).
    imputes_missing: bool = False

    def encode_imputed(self, inputs: Inputs, steps: int) -> Gaussian:
        """The posterior after ``steps`` rounds of imputing the modalities missing from
        ``inputs`` (see :meth:`prg.models.muse.MUSE.encode_imputed`). Families whose posterior
        does not combine modalities have nothing to impute: their plain :meth:`encode`."""
        return self.encode(inputs)

    @torch.no_grad()
    def generate(
        self,
        inputs: Inputs,
        target: str,
        n: int = 1,
        temperature: float = 0.0,
        impute_steps: int = 0,
    ) -> torch.Tensor:
        """Data-space outputs of ``target`` from ``inputs``.

        Parameters
        ----------
        inputs : dict
            Any subset the family supports.
        target : str
            Modality to generate.
        n : int
            Samples per input.
        temperature : float
            0 decodes the posterior mean (every sample equal; for a mixture posterior, the mean
            of one component drawn per sample, :meth:`prg.models.mixture.Mixture.sample`);
            otherwise latents are drawn with their standard deviation scaled by
            ``temperature``.
        impute_steps : int
            0 (the paper): the posterior of ``inputs`` alone; k > 0: the posterior after k
            rounds of imputing the missing modalities (:meth:`encode_imputed`).

        Returns
        -------
        Tensor, shape (n, B, ...)
            Trajectory means (n, B, 200), class probabilities (n, B, 62) or pixel
            probabilities (n, B, 1, 28, 28).
        """
        self._check_target(target)
        posterior = self.generation_posterior(inputs, impute_steps)
        return self.decode_posterior(posterior, inputs, target, n, temperature)

    def _check_target(self, target: str) -> None:
        if target not in self.generated_modalities:
            raise UsageError(
                f"{self.family} cannot generate {target!r}: it generates "
                f"{list(self.generated_modalities)}"
            )

    @torch.no_grad()
    def generation_posterior(self, inputs: Inputs, impute_steps: int = 0) -> Gaussian:
        """The posterior :meth:`generate` decodes from: :meth:`encode`, or
        :meth:`encode_imputed` with ``impute_steps`` > 0. A caller that decodes several targets
        from the same inputs computes it once and passes it to :meth:`decode_posterior`."""
        if isinstance(impute_steps, bool) or not isinstance(impute_steps, int) or impute_steps < 0:
            raise UsageError(f"impute_steps must be an integer >= 0, got {impute_steps!r}")
        return self.encode_imputed(inputs, impute_steps) if impute_steps else self.encode(inputs)

    @torch.no_grad()
    def decode_posterior(
        self,
        posterior: Gaussian,
        inputs: Inputs,
        target: str,
        n: int = 1,
        temperature: float = 0.0,
    ) -> torch.Tensor:
        """:meth:`generate`'s outputs from a posterior of ``inputs``
        (:meth:`generation_posterior`); ``inputs`` are the decoders' context."""
        self._check_target(target)
        z = posterior.sample(n, temperature)  # temperature 0: a mean (Mixture: a component's)
        flat = z.reshape(-1, z.shape[-1])
        context = None
        if inputs:
            context = {k: v.repeat(n, *([1] * (v.dim() - 1))) for k, v in inputs.items()}
        params = self.decode(flat, target, context)
        out = self.likelihoods.mean(target, params)
        return out.reshape(n, -1, *out.shape[1:])
