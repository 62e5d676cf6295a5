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
from prg.models.base import LETTER, Gaussian, ImportancePath, Inputs, MultimodalVAE
from prg.models.likelihoods import Likelihoods

_LOG_2PI = math.log(2 * math.pi)

DENSITY_CONVENTION = (
    "Log-likelihoods in nats per test sample (mean over samples, with its standard error). "
    "Trajectories: Gaussian, fixed std per coordinate (the models' `traj_std`, 0.1), "
    "normalising constants included, summed over the 200 coordinates. Labels: categorical "
    "log-probability (always <= 0). Images: Bernoulli log-likelihood of the grey targets in "
    "[0, 1] (minus the binary cross-entropy), summed over the 784 pixels - not a normalised "
    "density over grey images. Conditionals follow the reference code: proposal q(z | x_given), "
    "scored against the prior N(0, I) (an estimate of log p(x_target) with an x_given-informed "
    "proposal); the CVAE's log p(x_T | x_S) uses q(z | x_T, x_S)."
)

# Table I of the paper: name -> (target, given modalities)
TABLE1_CELLS: dict[str, tuple[str, tuple[str, ...]]] = {
    "logp_T": ("traj", ()),
    "logp_S": ("label", ()),
    "logp_I": ("image", ()),
    "logp_T_given_S": ("traj", ("label",)),
    "logp_T_given_I": ("traj", ("image",)),
    "logp_S_given_T": ("label", ("traj",)),
    "logp_I_given_T": ("image", ("traj",)),
}


def cell_name(target: str, given: tuple[str, ...], prefix: str = "logp") -> str:
    """``logp_T_given_S``-style name of ``log p(x_target | x_given)``."""
    name = f"{prefix}_{LETTER[target]}"
    return name + (f"_given_{''.join(LETTER[m] for m in given)}" if given else "")


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


@torch.no_grad()
def estimate_cell(
    model: MultimodalVAE,
    target: str,
    given: tuple[str, ...],
    data: Inputs,
    k: int,
    batch_size: int = 64,
    chunk_rows: int = 4096,
    seed: int = 0,
    progress: bool = False,
    likelihoods: Likelihoods | None = None,
) -> torch.Tensor:
    """``log p(x_target | x_given)`` per sample of ``data`` (dict of full-split tensors).

    Samples are taken ``batch_size`` at a time; importance samples ``chunk_rows // batch_size``
    at a time, so at most ``chunk_rows`` decoder outputs are alive at once whatever K is. The
    generator is seeded per cell, so a cell's value does not depend on which others are run.
    ``likelihoods`` replaces the model's own (e.g. another trajectory std, to compare with a
    paper that used another convention).

    Raises
    ------
    UsageError
        If the family cannot estimate this cell, or K < 1.
    """
    if not isinstance(k, int) or isinstance(k, bool) or k < 1:
        raise UsageError(f"number of importance samples K must be an integer >= 1, got {k!r}")
    model.check_cell(target, {m: data[m] for m in given})
    generator = torch.Generator().manual_seed(seed)
    n = len(data[target])
    chunk = max(1, chunk_rows // batch_size)
    out = torch.empty(n)
    starts = range(0, n, batch_size)
    if progress:
        from tqdm.auto import tqdm

        starts = tqdm(starts, desc=f"{model.family} {cell_name(target, given)} K={k}", leave=False)
    for start in starts:
        rows = slice(start, start + batch_size)
        path = model.importance_path(target, data[target][rows], {m: data[m][rows] for m in given})
        out[rows] = iw_log_likelihood(
            path, data[target][rows], likelihoods or model.likelihoods, k, chunk, generator
        )
    return out
