"""Importance-weighted log-likelihood estimates, vectorised and chunked over samples.

For an :class:`~prg.models.base.ImportancePath` (proposal q, decoder, target modality) and data
x, with ``z_k ~ q`` for k = 1..K::

    w_k = log p(x | decode(z_k)) + log N(z_k; 0, I) - log q(z_k)
    log p(x) ~= logmeanexp_k w_k

The K samples are drawn ``chunk`` at a time and folded into a running log-sum-exp, so memory is
bounded by ``chunk * batch`` decoder outputs whatever K is. The density convention is that of
:mod:`prg.models.likelihoods` (normalising constants included; Bernoulli on grey images).

Several likelihoods can be scored in one pass (:func:`iw_log_likelihoods`,
:func:`estimate_cell_multi`): the latent samples, the decoder outputs and the prior and proposal
terms are shared, only ``log p(x | decode(z_k))`` is evaluated once per likelihood, each into its
own running log-sum-exp. Table I uses this for trajectory targets, scored under a unit-variance
Gaussian (the paper's scale) and under the model's own std in the same pass; each estimate
equals the one a separate pass with the same seed would give.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import torch

from prg.errors import UsageError
from prg.evaluation.settings import PAPER_TRAJ_STD  # exported here too (the settings' default)
from prg.models.base import Gaussian, ImportancePath, Inputs, MultimodalVAE
from prg.models.likelihoods import Likelihoods
from prg.models.modalities import IMAGE, LABEL, LETTER, TRAJ

_LOG_2PI = math.log(2 * math.pi)

MODEL_STD_SUFFIX = "_model_std"
"""Suffix of a trajectory cell scored under the model's own std (``logp_T_model_std``), the
second table beside the main one."""


def density_convention(traj_std: float | None = PAPER_TRAJ_STD) -> str:
    """How Table I's numbers are defined; ``traj_std`` is the main table's trajectory std
    (None: each model's own)."""
    if traj_std is None:
        main = "each model's own std (its `traj_std`, 0.1 in every family's config)"
    else:
        unit = " (unit variance, the reference code's implicit choice)" if traj_std == 1.0 else ""
        main = f"std {traj_std:g} per coordinate{unit}"
    return (
        "Log-likelihoods in nats per test sample (mean over samples, with its standard error). "
        f"Trajectories: Gaussian around the decoded mean with {main}, normalising constants "
        "included, summed over the 200 coordinates. The second table scores the same "
        "importance samples under each model's own std (its `traj_std`, 0.1 in every family's "
        "config, the std it was trained with): its normalising constant "
        "-200 log(0.1 sqrt(2 pi)) = +277 nats is why those values are mostly positive, where "
        "unit variance contributes -200 log(sqrt(2 pi)) = -184 nats, and its squared error "
        "weighs 100 times more. Labels: categorical log-probability (always "
        "<= 0). Images: Bernoulli log-likelihood of the grey targets in [0, 1] (minus the "
        "binary cross-entropy), summed over the 784 pixels - not a normalised density over "
        "grey images. Label and image cells do not depend on the trajectory std. Conditionals "
        "follow the reference code: proposal q(z | x_given), scored against the prior N(0, I) "
        "(an estimate of log p(x_target) with an x_given-informed proposal); the CVAE's "
        "log p(x_T | x_S) uses q(z | x_T, x_S)."
    )


DENSITY_CONVENTION = density_convention()


def cell_name(target: str, given: tuple[str, ...], prefix: str = "logp") -> str:
    """``logp_T_given_S``-style name of ``log p(x_target | x_given)``."""
    name = f"{prefix}_{LETTER[target]}"
    return name + (f"_given_{''.join(LETTER[m] for m in given)}" if given else "")


# Table I of the paper: name (logp_T, logp_T_given_S ...) -> (target, given modalities)
TABLE1_CELLS: dict[str, tuple[str, tuple[str, ...]]] = {
    cell_name(target, given): (target, given)
    for target, given in [
        (TRAJ, ()),
        (LABEL, ()),
        (IMAGE, ()),
        (TRAJ, (LABEL,)),
        (TRAJ, (IMAGE,)),
        (LABEL, (TRAJ,)),
        (IMAGE, (TRAJ,)),
    ]
}


# Table I of Vital et al. (2022): augmented UJI Char Pen 2 test set, K = 1000 / 5000.
PAPER_TABLE1: dict[str, dict[str, float]] = {
    "cvae": {"logp_T_given_S": -192.75},
    "avae_ts": {
        "logp_T": -197.55,
        "logp_S": -4.17,
        "logp_T_given_S": -189.28,
        "logp_S_given_T": 1.94,
    },
    "avae_ti": {
        "logp_T": -197.69,
        "logp_I": -743.57,
        "logp_T_given_I": -186.28,
        "logp_I_given_T": -730.44,
    },
    "muse": {
        "logp_T": -198.04,
        "logp_S": -4.53,
        "logp_I": -742.49,
        "logp_T_given_S": -198.10,
        "logp_T_given_I": -193.63,
        "logp_S_given_T": 1.96,
        "logp_I_given_T": -735.02,
    },
}


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
        Proposal (batch shape (B, d); a Gaussian or a mixture of them), decoder and target
        modality.
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
    return iw_log_likelihoods(path, x, [likelihoods], k, chunk, generator)[0]


@torch.no_grad()
def iw_log_likelihoods(
    path: ImportancePath,
    x: torch.Tensor,
    likelihoods: Sequence[Likelihoods],
    k: int,
    chunk: int = 250,
    generator: torch.Generator | None = None,
) -> torch.Tensor:
    """:func:`iw_log_likelihood` under several likelihoods in one pass.

    The same K latent samples, decoder outputs, prior and proposal terms serve every
    likelihood; only ``log p(x | decode(z_k))`` is evaluated per likelihood, each into its own
    running log-sum-exp. Row ``i`` equals :func:`iw_log_likelihood` with ``likelihoods[i]``
    and an identically seeded generator.

    Returns
    -------
    Tensor, shape (len(likelihoods), B)
    """
    if not isinstance(k, int) or isinstance(k, bool) or k < 1:
        raise UsageError(f"number of importance samples K must be an integer >= 1, got {k!r}")
    if chunk < 1:
        raise UsageError(f"chunk must be >= 1, got {chunk}")
    if not likelihoods:
        raise UsageError("no likelihood to estimate under")
    proposal: Gaussian = path.proposal  # or a Mixture of them (the same sample, log_prob)
    batch = x.shape[0]
    shape = (len(likelihoods), batch)
    running_max = torch.full(shape, -math.inf, device=x.device)
    running_sum = torch.zeros(shape, device=x.device)
    done = 0
    while done < k:
        n = min(chunk, k - done)
        z = proposal.sample(n, generator=generator)  # (n, B, d)
        params = path.decode(z.reshape(n * batch, -1))
        params = params.reshape(n, batch, *params.shape[1:])
        latent = standard_normal_log_prob(z) - proposal.log_prob(z)  # (n, B)
        w = torch.stack(
            [lik.log_prob(path.target, params, x) + latent for lik in likelihoods], dim=1
        )  # (n, L, B)
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
    chosen = likelihoods or model.likelihoods
    return estimate_cell_multi(
        model, target, given, data, k, [chosen], batch_size, chunk_rows, seed, progress
    )[0]


@torch.no_grad()
def estimate_cell_multi(
    model: MultimodalVAE,
    target: str,
    given: tuple[str, ...],
    data: Inputs,
    k: int,
    likelihoods: Sequence[Likelihoods],
    batch_size: int = 64,
    chunk_rows: int = 4096,
    seed: int = 0,
    progress: bool = False,
) -> torch.Tensor:
    """:func:`estimate_cell` under each of ``likelihoods``, in one importance-sampling pass
    (shared latent samples and decoder outputs, :func:`iw_log_likelihoods`).

    Returns
    -------
    Tensor, shape (len(likelihoods), N)
        Row ``i`` equals ``estimate_cell(..., likelihoods=likelihoods[i])`` with the same seed.
    """
    if not isinstance(k, int) or isinstance(k, bool) or k < 1:
        raise UsageError(f"number of importance samples K must be an integer >= 1, got {k!r}")
    model.check_cell(target, {m: data[m] for m in given})
    generator = torch.Generator().manual_seed(seed)
    n = len(data[target])
    chunk = max(1, chunk_rows // batch_size)
    out = torch.empty(len(likelihoods), n)
    starts = range(0, n, batch_size)
    if progress:
        from tqdm.auto import tqdm

        starts = tqdm(starts, desc=f"{model.family} {cell_name(target, given)} K={k}", leave=False)
    for start in starts:
        rows = slice(start, start + batch_size)
        path = model.importance_path(target, data[target][rows], {m: data[m][rows] for m in given})
        out[:, rows] = iw_log_likelihoods(
            path, data[target][rows], likelihoods, k, chunk, generator
        )
    return out
