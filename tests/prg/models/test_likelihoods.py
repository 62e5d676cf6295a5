"""Per-modality likelihoods of prg.models.likelihoods against torch.distributions and formulas."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch
from numpy.testing import assert_allclose
from torch.distributions import Bernoulli, Categorical, Normal

from prg.models.likelihoods import Likelihoods

B, K = 5, 4


def _gen(seed: int) -> torch.Generator:
    return torch.Generator().manual_seed(seed)


@pytest.mark.parametrize("std", [0.1, 0.5, 2.0])
def test_traj_log_prob_is_a_summed_gaussian_log_density(std):
    g = _gen(0)
    mu, x = torch.randn(B, 200, generator=g), torch.randn(B, 200, generator=g)
    want = Normal(mu, std).log_prob(x).sum(-1)
    torch.testing.assert_close(Likelihoods(traj_std=std).log_prob("traj", mu, x), want)


def test_traj_log_prob_is_maximal_at_the_mean_with_the_normalising_constant():
    x = torch.zeros(1, 200)
    got = Likelihoods(traj_std=0.1).log_prob("traj", x, x)
    assert_allclose(got.numpy(), [-200 * math.log(0.1 * math.sqrt(2 * math.pi))], rtol=1e-6)


def test_label_log_prob_is_the_categorical_log_probability():
    g = _gen(1)
    logits = torch.randn(B, 62, generator=g) * 3
    y = torch.randint(0, 62, (B,), generator=g)
    want = Categorical(logits=logits).log_prob(y)
    torch.testing.assert_close(Likelihoods().log_prob("label", logits, y), want)


def test_image_log_prob_follows_the_bernoulli_formula_with_grey_targets():
    g = _gen(2)
    logits = torch.randn(B, 1, 28, 28, generator=g, dtype=torch.float64) * 2
    x = torch.rand(B, 1, 28, 28, generator=g, dtype=torch.float64)  # grey values in [0, 1]
    p = 1.0 / (1.0 + np.exp(-logits.numpy()))
    want = (x.numpy() * np.log(p) + (1 - x.numpy()) * np.log(1 - p)).reshape(B, -1).sum(-1)
    got = Likelihoods().log_prob("image", logits, x)
    assert got.shape == (B,)
    assert_allclose(got.numpy(), want, rtol=1e-10)


def test_image_log_prob_on_binary_targets_is_the_bernoulli_log_probability():
    g = _gen(3)
    logits = torch.randn(B, 1, 28, 28, generator=g)
    x = (torch.rand(B, 1, 28, 28, generator=g) > 0.5).float()
    want = Bernoulli(logits=logits).log_prob(x).flatten(1).sum(-1)
    torch.testing.assert_close(Likelihoods().log_prob("image", logits, x), want)


def _params_and_data(modality: str, g: torch.Generator):
    if modality == "traj":
        return torch.randn(K, B, 200, generator=g), torch.randn(B, 200, generator=g)
    if modality == "label":
        return torch.randn(K, B, 62, generator=g), torch.randint(0, 62, (B,), generator=g)
    return torch.randn(K, B, 1, 28, 28, generator=g), torch.rand(B, 1, 28, 28, generator=g)


@pytest.mark.parametrize("modality", ["traj", "label", "image"])
def test_log_prob_broadcasts_a_leading_sample_dimension_over_the_data(modality):
    """Importance sampling decodes K latents per sample: params (K, B, ...) against x (B, ...)."""
    params, x = _params_and_data(modality, _gen(4))
    lik = Likelihoods(traj_std=0.3)
    got = lik.log_prob(modality, params, x)
    assert got.shape == (K, B)
    want = torch.stack([lik.log_prob(modality, params[k], x) for k in range(K)])
    torch.testing.assert_close(got, want)


def test_mean_of_traj_is_the_decoder_output():
    params = torch.randn(B, 200, generator=_gen(5))
    torch.testing.assert_close(Likelihoods.mean("traj", params), params)


def test_mean_of_label_is_a_probability_vector_ordered_like_the_logits():
    logits = torch.randn(K, B, 62, generator=_gen(6))
    probs = Likelihoods.mean("label", logits)
    torch.testing.assert_close(probs.sum(-1), torch.ones(K, B))
    assert (probs >= 0).all()
    torch.testing.assert_close(probs.argmax(-1), logits.argmax(-1))


def test_mean_of_image_is_the_pixel_probability():
    logits = torch.tensor([[-50.0, 0.0, 50.0]])
    assert_allclose(Likelihoods.mean("image", logits).numpy(), [[0.0, 0.5, 1.0]], atol=1e-12)


def test_unknown_modality_is_refused_by_log_prob_and_mean():
    with pytest.raises(ValueError, match="unknown modality 'sound'"):
        Likelihoods().log_prob("sound", torch.zeros(1), torch.zeros(1))
    with pytest.raises(ValueError, match="unknown modality 'sound'"):
        Likelihoods.mean("sound", torch.zeros(1))


@pytest.mark.parametrize("std", [0.0, -1.0])
def test_non_positive_traj_std_is_refused(std):
    with pytest.raises(ValueError, match="traj_std must be > 0"):
        Likelihoods(traj_std=std)
