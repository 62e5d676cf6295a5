"""Tests of ``prg.models.mixture``: the mixture's density by hand, its sampling (temperature 0:
a component's mean per sample), and the importance estimator with a mixture proposal."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from prg.evaluation.likelihood import iw_log_likelihood
from prg.models.base import Gaussian, ImportancePath
from prg.models.likelihoods import Likelihoods
from prg.models.mixture import Mixture, log_mean_exp, mixture_of, nonempty_subsets
from tests.helpers.baselines import gauss_logpdf

A = Gaussian(torch.tensor([[0.0, 1.0], [2.0, -1.0]]), torch.tensor([[0.0, -1.0], [0.5, 0.0]]))
B = Gaussian(torch.tensor([[3.0, -2.0], [-1.0, 0.5]]), torch.tensor([[-0.5, 0.3], [0.0, 1.0]]))


def test_log_prob_is_the_log_of_the_mean_component_density():
    z = torch.tensor([[[0.5, 0.2], [1.0, 0.0]], [[2.0, -1.0], [-1.0, 1.0]]])  # (2, 2, 2)
    by_hand = np.log(
        0.5
        * np.exp(
            gauss_logpdf(z.double().numpy(), A.mu.double().numpy(), A.logvar.exp().double().numpy())
        )
        + 0.5
        * np.exp(
            gauss_logpdf(z.double().numpy(), B.mu.double().numpy(), B.logvar.exp().double().numpy())
        )
    )
    np.testing.assert_allclose(Mixture([A, B]).log_prob(z).numpy(), by_hand, rtol=1e-5)


def test_temperature_zero_gives_one_components_mean_per_sample():
    torch.manual_seed(0)
    z = Mixture([A, B]).sample(200, temperature=0.0)
    assert z.shape == (200, 2, 2)
    is_a = (z == A.mu).all(-1)
    is_b = (z == B.mu).all(-1)
    assert (is_a ^ is_b).all()  # exactly one component's mean, chosen per sample and row
    assert 0.35 < is_a.float().mean() < 0.65
    assert Mixture([A, B]).sample(temperature=0.0).shape == (2, 2)


def test_samples_follow_the_mixture():
    g = torch.Generator().manual_seed(0)
    z = Mixture([A, B]).sample(20000, generator=g)
    expected = (A.mu + B.mu) / 2
    torch.testing.assert_close(z.mean(0), expected, atol=0.05, rtol=0)
    torch.testing.assert_close(Mixture([A, B]).mean, expected)
    second = (A.logvar.exp() + A.mu**2 + B.logvar.exp() + B.mu**2) / 2
    torch.testing.assert_close((z**2).mean(0), second, atol=0.15, rtol=0)


def test_a_mixture_proposal_gives_the_hand_importance_estimate():
    """K = 3 draws from a seeded generator, redrawn here; the estimate must be
    logmeanexp_k [log p(x | z_k) + log N(z_k; 0, I) - log q(z_k)] with q the mixture."""
    q = Mixture([A, B])
    x = torch.tensor([[0.1] * 4, [-0.2] * 4])
    w = torch.tensor([[1.0, 0.0, -1.0, 0.5], [0.5, 1.0, 0.0, -0.5]])  # decoder z (2) -> 4

    def decode(z):
        return z @ w

    path = ImportancePath(q, decode, "traj", 2)
    got = iw_log_likelihood(
        path, x, Likelihoods(traj_std=0.1), k=3, chunk=3, generator=torch.Generator().manual_seed(5)
    )
    z = q.sample(3, generator=torch.Generator().manual_seed(5)).double().numpy()
    mean = z @ w.double().numpy()
    log_px = -((x.double().numpy() - mean) ** 2).sum(-1) / (2 * 0.01) - 4 * math.log(
        0.1 * math.sqrt(2 * math.pi)
    )
    log_prior = (-0.5 * (z**2 + math.log(2 * math.pi))).sum(-1)
    log_q = np.log(
        0.5 * np.exp(gauss_logpdf(z, A.mu.double().numpy(), A.logvar.exp().double().numpy()))
        + 0.5 * np.exp(gauss_logpdf(z, B.mu.double().numpy(), B.logvar.exp().double().numpy()))
    )
    lw = log_px + log_prior - log_q
    by_hand = np.log(np.exp(lw - lw.max(0)).mean(0)) + lw.max(0)
    np.testing.assert_allclose(got.numpy(), by_hand, rtol=1e-4)


def test_helpers():
    assert mixture_of([A]) is A
    assert isinstance(mixture_of([A, B]), Mixture)
    assert nonempty_subsets(("a", "b", "c"))[-1] == ("a", "b", "c")
    assert len(nonempty_subsets(("a", "b", "c"))) == 7
    assert float(log_mean_exp(torch.tensor([0.0, math.log(3.0)]))) == pytest.approx(math.log(2))
    with pytest.raises(ValueError, match="at least one component"):
        Mixture([])
