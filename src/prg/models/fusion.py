"""Gaussian algebra shared by the model families: product of experts, KL, symmetric KL."""

from __future__ import annotations

import torch


def product_of_experts(
    mus: list[torch.Tensor], logvars: list[torch.Tensor], prior_expert: bool = True
) -> tuple[torch.Tensor, torch.Tensor]:
    """Product of diagonal Gaussian experts (optionally with the prior expert N(0, I)).

    The product of N(mu_i, var_i) is Gaussian with precision ``T = sum_i 1 / var_i`` and mean
    ``(sum_i mu_i / var_i) / T``; the prior expert adds 1 to the precision and 0 to the
    numerator.

    Parameters
    ----------
    mus, logvars : list of Tensor, each shape (..., d)
        One entry per available expert (a missing modality is simply left out).
    prior_expert : bool
        Include N(0, I).

    Returns
    -------
    mu, logvar : Tensor, shape (..., d)
    """
    if len(mus) != len(logvars):
        raise ValueError("product_of_experts needs one logvar per mu")
    if not mus:
        raise ValueError("product_of_experts needs at least one expert (the prior has no shape)")
    precisions = torch.stack([torch.exp(-lv) for lv in logvars])
    precision = precisions.sum(0) + (1.0 if prior_expert else 0.0)
    mean = (torch.stack(mus) * precisions).sum(0) / precision
    return mean, -torch.log(precision)


def kl_standard_normal(mu: torch.Tensor, logvar: torch.Tensor) -> torch.Tensor:
    """KL(N(mu, exp(logvar)) || N(0, I)), summed over the last dimension."""
    return 0.5 * (mu.pow(2) + logvar.exp() - 1.0 - logvar).sum(-1)


def kl_normal(
    mu_q: torch.Tensor, logvar_q: torch.Tensor, mu_p: torch.Tensor, logvar_p: torch.Tensor
) -> torch.Tensor:
    """KL(q || p) between diagonal Gaussians, summed over the last dimension."""
    var_ratio = (logvar_q - logvar_p).exp()
    return 0.5 * (
        var_ratio + (mu_q - mu_p).pow(2) / logvar_p.exp() - 1.0 - (logvar_q - logvar_p)
    ).sum(-1)


def symmetric_kl(
    mu_a: torch.Tensor, logvar_a: torch.Tensor, mu_b: torch.Tensor, logvar_b: torch.Tensor
) -> torch.Tensor:
    """KL(a || b) + KL(b || a), summed over the last dimension."""
    return kl_normal(mu_a, logvar_a, mu_b, logvar_b) + kl_normal(mu_b, logvar_b, mu_a, logvar_a)


def reparameterise(mu: torch.Tensor, logvar: torch.Tensor, eps: torch.Tensor | None = None):
    """``mu + sigma * eps`` with ``eps ~ N(0, I)`` unless given."""
    if eps is None:
        eps = torch.randn_like(mu)
    return mu + torch.exp(0.5 * logvar) * eps
