"""Tests of ``prg.models.base`` (moved from the suite on: gaussian algebra of prg.models.fusion
against independent computations.

The product of experts is checked against a brute-force product of densities on a 1-D grid and
against pairwise variance-form algebra (a different formula from the precision form the code
uses); the KLs against ``torch.distributions.kl_divergence``)."""

from __future__ import annotations

import torch
from numpy.testing import assert_allclose
from torch.distributions import Normal

from prg.models.base import Gaussian
from tests.helpers.fusion import _normal_pair


def test_gaussian_log_prob_matches_torch_distributions():
    mu, logvar, z, _ = _normal_pair(7)
    want = Normal(mu, (0.5 * logvar).exp()).log_prob(z).sum(-1)
    torch.testing.assert_close(Gaussian(mu, logvar).log_prob(z), want)


def test_gaussian_samples_have_the_stated_moments_and_temperature_scales_spread():
    torch.manual_seed(0)
    mu = torch.tensor([1.0, -2.0, 0.5])
    logvar = torch.log(torch.tensor([0.25, 4.0, 1.0]))
    q = Gaussian(mu, logvar)
    z = q.sample(200_000)
    assert z.shape == (200_000, 3)
    assert_allclose(z.mean(0).numpy(), mu.numpy(), atol=0.02)
    assert_allclose(z.std(0).numpy(), [0.5, 2.0, 1.0], rtol=0.01)
    z_cold = q.sample(200_000, temperature=0.5)
    assert_allclose(z_cold.std(0).numpy(), [0.25, 1.0, 0.5], rtol=0.01)
