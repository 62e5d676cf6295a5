"""Importance-weighted log-likelihood estimates, vectorised and chunked over samples.

For an :class:`~prg.models.base.ImportancePath` (proposal q, decoder, target modality) and data
x, with ``z_k ~ q`` for k = 1..K::

    w_k = log p(x | decode(z_k)) + log N(z_k; 0, I) - log q(z_k)
    log p(x) ~= logmeanexp_k w_k

The K samples are drawn ``chunk`` at a time and folded into a running log-sum-exp, so memory is
bounded by ``chunk * batch`` decoder outputs whatever K is. The density convention is that of
:mod:`prg.models.likelihoods` (normalising constants included; Bernoulli on grey images).
"""

from __future__ import annotations

import math

import torch

from prg.errors import UsageError
from prg.models.base import Gaussian, ImportancePath
from prg.models.likelihoods import Likelihoods

_LOG_2PI = math.log(2 * math.pi)


def standard_normal_log_prob(z: torch.Tensor) -> torch.Tensor:
    """log N(z; 0, I) summed over the last dimension."""
    return -0.5 * (z.pow(2) + _LOG_2PI).sum(-1)


@torch.no_grad()
def iw_log_likelihood(
    path: ImportancePath,
    x: torch.Tensor,
    likelihoods: Likelihoods,
    k: int,
    chunk: int = 250,
    generator: torch.Generator | None = None,
) -> torch.Tensor:
    """Importance-weighted estimate of ``log p(x)`` per sample.

    Parameters
    ----------
    path : ImportancePath
        Proposal (batch shape (B, d)), decoder and target modality.
    x : Tensor
        Target data, batch size B.
    likelihoods : Likelihoods
        The model's likelihoods (``model.likelihoods``).
    k : int
        Importance samples per data point (>= 1).
    chunk : int
        Samples drawn per step; peak memory ~ ``chunk * B`` decoder outputs.
    generator : torch.Generator, optional
        Makes the estimate deterministic.

    Returns
    -------
    Tensor, shape (B,)
    """
    if not isinstance(k, int) or k < 1:
        raise UsageError(f"number of importance samples K must be an integer >= 1, got {k!r}")
    if chunk < 1:
        raise UsageError(f"chunk must be >= 1, got {chunk}")
    proposal: Gaussian = path.proposal
    batch = proposal.mu.shape[0]
    running_max = torch.full((batch,), -math.inf, device=proposal.mu.device)
    running_sum = torch.zeros(batch, device=proposal.mu.device)
    std = torch.exp(0.5 * proposal.logvar)
    done = 0
    while done < k:
        n = min(chunk, k - done)
        eps = torch.randn((n, *proposal.mu.shape), generator=generator, device=proposal.mu.device)
        z = proposal.mu + std * eps  # (n, B, d)
        params = path.decode(z.reshape(n * batch, -1))
        params = params.reshape(n, batch, *params.shape[1:])
        w = (
            likelihoods.log_prob(path.target, params, x)
            + standard_normal_log_prob(z)
            - proposal.log_prob(z)
        )  # (n, B)
        chunk_max = w.max(dim=0).values
        new_max = torch.maximum(running_max, chunk_max)
        running_sum = running_sum * torch.exp(running_max - new_max) + torch.exp(w - new_max).sum(0)
        running_max = new_max
        done += n
    return running_max + torch.log(running_sum) - math.log(k)
