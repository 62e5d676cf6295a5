"""Mixtures of diagonal Gaussians and the subset algebra of the baseline families.

The mixture-of-experts posteriors of MMVAE (Shi et al. 2019) and MoPoE (Sutter et al. 2021) are
uniform mixtures of diagonal Gaussians. :class:`Mixture` has the duck interface of
:class:`~prg.models.base.Gaussian` that the rest of the project uses (``sample``, ``log_prob``,
``mean``), so a mixture serves as an importance-sampling proposal
(:func:`prg.evaluation.likelihood.iw_log_likelihood`) and as a posterior to generate from.

Temperature 0 (``sample(n, 0)``, the project's "posterior mean" decoding) returns the mean of
one component per sample, drawn uniformly: a latent the model decodes from one input subset's
posterior. The mixture's own mean, the average of the component means (what MultiVae's
``encode(..., return_mean=True)`` decodes for MMVAE), can sit between two components, where no
component puts mass, and decodes to a blend of what they would write.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import combinations

import torch

from prg.models.base import Gaussian


def log_mean_exp(x: torch.Tensor, dim: int = 0) -> torch.Tensor:
    """``log(mean(exp(x)))`` along ``dim``, computed stably (log-sum-exp minus log n).

    Examples
    --------
    >>> float(log_mean_exp(torch.tensor([0.0, 0.0])))
    0.0
    """
    return torch.logsumexp(x, dim) - math.log(x.shape[dim])


def nonempty_subsets(modalities: Sequence[str]) -> list[tuple[str, ...]]:
    """Every non-empty subset, smallest first, each in the given order (7 for 3 modalities).

    Examples
    --------
    >>> nonempty_subsets(("traj", "label"))
    [('traj',), ('label',), ('traj', 'label')]
    """
    return [s for r in range(1, len(modalities) + 1) for s in combinations(modalities, r)]


@dataclass
class Mixture:
    """Uniform mixture of diagonal Gaussians with the same batch shape (..., d).

    Parameters
    ----------
    components : list of Gaussian
        The mixture's components, each with weight ``1 / len(components)``.

    Examples
    --------
    >>> q = Mixture([Gaussian(torch.zeros(1, 2), torch.zeros(1, 2))] * 2)
    >>> q.sample(3).shape
    torch.Size([3, 1, 2])
    """

    components: list[Gaussian]

    def __post_init__(self) -> None:
        if not self.components:
            raise ValueError("a mixture needs at least one component")

    def _stacked(self) -> tuple[torch.Tensor, torch.Tensor]:
        return (
            torch.stack([c.mu for c in self.components]),
            torch.stack([c.logvar for c in self.components]),
        )  # (C, ..., d) each

    def sample(
        self,
        n: int | None = None,
        temperature: float = 1.0,
        generator: torch.Generator | None = None,
    ) -> torch.Tensor:
        """One component per sample (uniformly), then a draw from it with its standard
        deviation scaled by ``temperature`` (0: that component's mean).

        Returns
        -------
        Tensor, shape (n, ..., d) (or (..., d) when ``n`` is None)
        """
        mus, logvars = self._stacked()
        batch = mus.shape[1:-1]
        shape = batch if n is None else (n, *batch)
        pick = torch.randint(len(self.components), shape, generator=generator, device=mus.device)
        index = pick[None, ..., None].expand(1, *shape, mus.shape[-1])
        full = (len(self.components), *shape, mus.shape[-1])
        view = (len(self.components), *([1] * (len(shape) - len(batch))), *mus.shape[1:])
        mu = mus.reshape(view).expand(full).gather(0, index)[0]
        if temperature == 0:
            return mu
        logvar = logvars.reshape(view).expand(full).gather(0, index)[0]
        eps = torch.randn(mu.shape, generator=generator, device=mu.device, dtype=mu.dtype)
        return mu + torch.exp(0.5 * logvar) * eps * temperature

    def log_prob(self, z: torch.Tensor) -> torch.Tensor:
        """``log (1/C) sum_c N(z; mu_c, var_c)``, summed over the last dimension."""
        return log_mean_exp(torch.stack([c.log_prob(z) for c in self.components]), 0)

    @property
    def mean(self) -> torch.Tensor:
        """E[z], the average of the component means, shape (..., d)."""
        return torch.stack([c.mu for c in self.components]).mean(0)


def mixture_of(components: list[Gaussian]) -> Gaussian | Mixture:
    """A :class:`Mixture` of ``components``, or the one Gaussian itself when there is one."""
    return components[0] if len(components) == 1 else Mixture(list(components))
