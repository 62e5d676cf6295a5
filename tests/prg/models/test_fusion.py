"""Tests of ``prg.models.fusion`` (moved from the suite on: gaussian algebra of prg.models.fusion
against independent computations.

The product of experts is checked against a brute-force product of densities on a 1-D grid and
against pairwise variance-form algebra (a different formula from the precision form the code
uses); the KLs against ``torch.distributions.kl_divergence``)."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from numpy.testing import assert_allclose
from torch.distributions import Normal, kl_divergence

from prg.models.fusion import (
    kl_normal,
    kl_standard_normal,
    product_of_experts,
    reparameterise,
    symmetric_kl,
)
from tests.helpers.fusion import _normal_pair


def _experts(n: int, shape: tuple[int, ...], seed: int = 0):
    g = torch.Generator().manual_seed(seed)
    mus = [torch.randn(shape, generator=g, dtype=torch.float64) * 2 for _ in range(n)]
    logvars = [torch.randn(shape, generator=g, dtype=torch.float64) for _ in range(n)]
    return mus, logvars


def _grid_product(mus: list[float], variances: list[float]) -> tuple[float, float]:
    """Mean and variance of the normalised product of 1-D Gaussian densities, by quadrature."""
    x = np.linspace(-30.0, 30.0, 600_001)
    log_density = np.zeros_like(x)
    for mu, var in zip(mus, variances):
        log_density += -0.5 * (x - mu) ** 2 / var - 0.5 * np.log(2 * np.pi * var)
    density = np.exp(log_density - log_density.max())
    density /= density.sum()
    mean = float((x * density).sum())
    return mean, float(((x - mean) ** 2 * density).sum())


@pytest.mark.parametrize("prior", [True, False])
@pytest.mark.parametrize("n_experts", [1, 2, 3])
def test_product_of_experts_matches_product_of_densities_on_a_grid(n_experts, prior):
    mus, logvars = _experts(n_experts, (1,), seed=n_experts)
    mu, logvar = product_of_experts(mus, logvars, prior_expert=prior)

    grid_mus = [float(m) for m in mus] + ([0.0] if prior else [])
    grid_vars = [float(lv.exp()) for lv in logvars] + ([1.0] if prior else [])
    want_mean, want_var = _grid_product(grid_mus, grid_vars)
    assert_allclose(float(mu), want_mean, rtol=1e-5, atol=1e-6)
    assert_allclose(float(logvar.exp()), want_var, rtol=1e-4)


@pytest.mark.parametrize("prior", [True, False])
@pytest.mark.parametrize("n_experts", [1, 2, 3])
def test_product_of_experts_matches_pairwise_variance_algebra_on_batched_shapes(n_experts, prior):
    # (K, B, d) leading dimensions, as an importance sampler or a batch of subsets would use.
    shape = (3, 4, 5)
    mus, logvars = _experts(n_experts, shape, seed=10 + n_experts)
    mu, logvar = product_of_experts(mus, logvars, prior_expert=prior)

    # Fold the experts in one at a time with the variance form of the product of two Gaussians:
    # var = v1 v2 / (v1 + v2), mean = (m1 v2 + m2 v1) / (v1 + v2).
    terms = [(m.numpy(), lv.exp().numpy()) for m, lv in zip(mus, logvars)]
    if prior:
        terms.append((np.zeros(shape), np.ones(shape)))
    want_mu, want_var = terms[0]
    for m2, v2 in terms[1:]:
        want_mu, want_var = (
            (want_mu * v2 + m2 * want_var) / (want_var + v2),
            want_var * v2 / (want_var + v2),
        )
    assert mu.shape == shape
    assert logvar.shape == shape
    assert_allclose(mu.numpy(), want_mu, rtol=1e-10, atol=1e-12)
    assert_allclose(logvar.exp().numpy(), want_var, rtol=1e-10)


def test_product_of_experts_treats_every_batch_element_independently():
    mus, logvars = _experts(2, (6, 3), seed=3)
    mu, logvar = product_of_experts(mus, logvars)
    for i in range(6):
        mu_i, logvar_i = product_of_experts([m[i] for m in mus], [lv[i] for lv in logvars])
        torch.testing.assert_close(mu[i], mu_i)
        torch.testing.assert_close(logvar[i], logvar_i)


def test_single_expert_without_prior_is_returned_unchanged():
    mus, logvars = _experts(1, (4, 8), seed=4)
    mu, logvar = product_of_experts(mus, logvars, prior_expert=False)
    torch.testing.assert_close(mu, mus[0])
    torch.testing.assert_close(logvar, logvars[0])


def test_prior_expert_shrinks_mean_and_variance_of_a_single_expert():
    mu, logvar = product_of_experts([torch.tensor([4.0])], [torch.tensor([0.0])])
    # N(4, 1) * N(0, 1) -> N(2, 1/2)
    torch.testing.assert_close(mu, torch.tensor([2.0]))
    torch.testing.assert_close(logvar, torch.log(torch.tensor([0.5])))


def test_product_of_experts_refuses_no_experts():
    with pytest.raises(ValueError, match="at least one expert"):
        product_of_experts([], [])


def test_product_of_experts_refuses_mismatched_mu_and_logvar_lists():
    mus, logvars = _experts(2, (2, 3))
    with pytest.raises(ValueError, match="one logvar per mu"):
        product_of_experts(mus, logvars[:1])


def test_product_of_experts_refuses_experts_of_different_shapes():
    with pytest.raises((ValueError, RuntimeError)):
        product_of_experts(
            [torch.zeros(2, 3), torch.zeros(2, 4)], [torch.zeros(2, 3), torch.zeros(2, 4)]
        )


def test_kl_standard_normal_matches_torch_distributions():
    mu, logvar, _, _ = _normal_pair(0)
    want = kl_divergence(Normal(mu, (0.5 * logvar).exp()), Normal(0.0, 1.0)).sum(-1)
    torch.testing.assert_close(kl_standard_normal(mu, logvar), want)


def test_kl_normal_matches_torch_distributions():
    mu_q, lv_q, mu_p, lv_p = _normal_pair(1)
    want = kl_divergence(Normal(mu_q, (0.5 * lv_q).exp()), Normal(mu_p, (0.5 * lv_p).exp())).sum(-1)
    torch.testing.assert_close(kl_normal(mu_q, lv_q, mu_p, lv_p), want)


def test_kl_normal_against_standard_normal_equals_kl_standard_normal():
    mu, logvar, _, _ = _normal_pair(2)
    zeros = torch.zeros_like(mu)
    torch.testing.assert_close(kl_normal(mu, logvar, zeros, zeros), kl_standard_normal(mu, logvar))


def test_symmetric_kl_is_the_sum_of_both_directions():
    mu_a, lv_a, mu_b, lv_b = _normal_pair(3)
    qa, qb = Normal(mu_a, (0.5 * lv_a).exp()), Normal(mu_b, (0.5 * lv_b).exp())
    want = (kl_divergence(qa, qb) + kl_divergence(qb, qa)).sum(-1)
    torch.testing.assert_close(symmetric_kl(mu_a, lv_a, mu_b, lv_b), want)


def test_symmetric_kl_is_symmetric():
    mu_a, lv_a, mu_b, lv_b = _normal_pair(4)
    torch.testing.assert_close(
        symmetric_kl(mu_a, lv_a, mu_b, lv_b), symmetric_kl(mu_b, lv_b, mu_a, lv_a)
    )


def test_symmetric_kl_is_zero_for_equal_inputs_and_positive_otherwise():
    mu_a, lv_a, mu_b, lv_b = _normal_pair(5)
    torch.testing.assert_close(symmetric_kl(mu_a, lv_a, mu_a, lv_a), torch.zeros(7))
    assert (symmetric_kl(mu_a, lv_a, mu_b, lv_b) > 0).all()


def test_reparameterise_with_given_noise_is_mean_plus_std_times_noise():
    mu, logvar, eps, _ = _normal_pair(6)
    torch.testing.assert_close(reparameterise(mu, logvar, eps), mu + logvar.exp().sqrt() * eps)


def test_kls_sum_over_the_last_dimension_of_batched_shapes():
    # (K, B, d) as the importance sampler uses them: the sum must run over d only
    g = torch.Generator().manual_seed(8)
    mu_q, lv_q, mu_p, lv_p = (torch.randn(3, 4, 5, generator=g) for _ in range(4))
    qn, pn = Normal(mu_q, (0.5 * lv_q).exp()), Normal(mu_p, (0.5 * lv_p).exp())
    torch.testing.assert_close(kl_normal(mu_q, lv_q, mu_p, lv_p), kl_divergence(qn, pn).sum(-1))
    torch.testing.assert_close(
        kl_standard_normal(mu_q, lv_q), kl_divergence(qn, Normal(0.0, 1.0)).sum(-1)
    )
    want = (kl_divergence(qn, pn) + kl_divergence(pn, qn)).sum(-1)
    torch.testing.assert_close(symmetric_kl(mu_q, lv_q, mu_p, lv_p), want)


def test_reparameterise_without_noise_draws_standard_normal_noise_scaled_by_sigma():
    mu = torch.tensor([1.0, -2.0, 0.5]).expand(100_000, 3)
    logvar = torch.log(torch.tensor([0.25, 4.0, 1.0])).expand(100_000, 3)
    torch.manual_seed(3)
    z = reparameterise(mu, logvar)
    torch.manual_seed(3)
    torch.testing.assert_close(z, mu + logvar.exp().sqrt() * torch.randn(100_000, 3))
    assert_allclose(z.mean(0).numpy(), [1.0, -2.0, 0.5], atol=0.03)
    assert_allclose(z.std(0).numpy(), [0.5, 2.0, 1.0], rtol=0.02)
