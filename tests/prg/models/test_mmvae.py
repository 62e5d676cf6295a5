"""Tests of ``prg.models.mmvae``: the stratified importance-weighted bound against a hand
computation, the DReG gradient's value and decoder gradient, training on the small dataset, and
the interface (mixture posteriors) over every input subset."""

from __future__ import annotations

from itertools import combinations

import numpy as np
import pytest
import torch

from prg.errors import UsageError
from prg.evaluation.likelihood import iw_log_likelihood
from prg.models.base import Gaussian
from prg.models.mixture import Mixture
from prg.models.mmvae import MMVAE
from tests.helpers.baselines import (
    FixedExpert,
    gauss_logpdf,
    label_logp,
    linear_decoder,
    logmeanexp,
    loss_falls,
    small_batches,
    traj_logp,
    weights_of,
)
from tests.helpers.models import ALL, make_batch

SUBSETS = [s for r in (1, 2, 3) for s in combinations(ALL, r)]

# two samples, latent 2, K = 3
MU_T, LV_T = [[0.5, -1.0], [0.2, 0.3]], [[-0.5, 0.2], [0.1, -1.0]]
MU_S, LV_S = [[-0.3, 0.8], [1.0, 0.0]], [[0.3, -0.7], [-0.2, 0.4]]
RNG = np.random.default_rng(7)
EPS = {"T": RNG.standard_normal((3, 2, 2)), "S": RNG.standard_normal((3, 2, 2))}


def tiny_mmvae(**kwargs) -> MMVAE:
    torch.manual_seed(0)
    model = MMVAE(("traj", "label"), latent_dim=2, k=3, **kwargs)
    model.experts["traj"] = FixedExpert(MU_T, LV_T)
    model.experts["label"] = FixedExpert(MU_S, LV_S)
    model.decoders["traj"] = linear_decoder(2, 200, seed=1)
    model.decoders["label"] = linear_decoder(2, 62, seed=2)
    noise = [torch.tensor(EPS[c], dtype=torch.float32) for c in ("T", "S")]
    model.noise = lambda like, k: noise.pop(0)
    return model


def tiny_batch():
    g = torch.Generator().manual_seed(3)
    return {"traj": torch.randn(2, 200, generator=g) * 0.3, "label": torch.tensor([4, 17])}


def test_loss_is_the_stratified_importance_bound_computed_by_hand():
    model = tiny_mmvae(weights={"traj": 1.0, "label": 50.0})
    batch = tiny_batch()
    terms = model.elbo(batch)

    x, y = batch["traj"].double().numpy(), batch["label"].numpy()
    (w_t, b_t), (w_s, b_s) = weights_of(model.decoders["traj"]), weights_of(model.decoders["label"])
    q = {"T": (np.array(MU_T), np.exp(LV_T)), "S": (np.array(MU_S), np.exp(LV_S))}
    bound = 0.0
    for c in ("T", "S"):
        z = q[c][0] + np.sqrt(q[c][1]) * EPS[c]  # (K, B, d)
        log_q = np.log(
            0.5 * np.exp(gauss_logpdf(z, *q["T"])) + 0.5 * np.exp(gauss_logpdf(z, *q["S"]))
        )
        log_w = (
            gauss_logpdf(z, 0.0, 1.0)
            + traj_logp(z @ w_t.T + b_t, x)
            + 50.0 * label_logp(z @ w_s.T + b_s, y)
            - log_q
        )
        component = logmeanexp(log_w, 0)
        assert terms[f"iwae_{'traj' if c == 'T' else 'label'}"].item() == pytest.approx(
            component.mean(), rel=1e-4
        )
        bound = bound + component / 2
    assert terms["loss"].item() == pytest.approx(-bound.mean(), rel=1e-4)


def test_dreg_keeps_the_value_and_the_decoders_gradient_and_changes_the_encoders():
    grads = {}
    for dreg in (False, True):
        model = tiny_mmvae(dreg=dreg)
        loss = model.elbo(tiny_batch())["loss"]
        loss.backward()
        grads[dreg] = (
            loss.item(),
            model.decoders["traj"].weight.grad.clone(),
            model.experts["traj"].mu.grad.clone(),
        )
    assert grads[True][0] == pytest.approx(grads[False][0], rel=1e-6)
    torch.testing.assert_close(grads[True][1], grads[False][1], rtol=1e-4, atol=1e-3)
    assert not torch.allclose(grads[True][2], grads[False][2])


def test_mmvae_trains_on_the_small_dataset(small_dataset):
    torch.manual_seed(0)
    first, last = loss_falls(MMVAE(k=1, dreg=True), small_batches(small_dataset))
    print(f"mmvae loss {first:.0f} -> {last:.0f}")
    assert last < 0.7 * first


@pytest.mark.parametrize("subset", SUBSETS, ids=lambda s: "+".join(s))
def test_every_subset_encodes_generates_and_proposes(subset):
    torch.manual_seed(0)
    model = MMVAE().eval()
    inputs = make_batch(3, modalities=subset)
    q = model.encode(inputs)
    if len(subset) == 1:
        assert isinstance(q, Gaussian) and q.mu.shape == (3, 16)
    else:
        assert isinstance(q, Mixture) and len(q.components) == len(subset)
        means = [model.experts[m](inputs[m])[0] for m in subset]
        for c, mean in zip(q.components, means, strict=True):
            torch.testing.assert_close(c.mu, mean)
    for target in ALL:
        out = model.generate(inputs, target, n=4)
        assert out.shape[:2] == (4, 3) and torch.isfinite(out).all()
        if target not in subset:
            x = make_batch(3, modalities=(target,))[target]
            path = model.importance_path(target, x, inputs)
            estimate = iw_log_likelihood(path, x, model.likelihoods, k=4)
            assert estimate.shape == (3,) and torch.isfinite(estimate).all()


def test_temperature_zero_decodes_one_experts_mean_per_sample():
    torch.manual_seed(0)
    model = MMVAE(("traj", "label")).eval()
    inputs = make_batch(2, modalities=("traj", "label"))
    out = model.generate(inputs, "traj", n=30)
    from_each = [model.generate({m: inputs[m]}, "traj")[0] for m in ("traj", "label")]
    matches = [torch.isclose(out, f, atol=1e-5).all(-1) for f in from_each]
    assert (matches[0] ^ matches[1]).all()  # each output is one expert's decoded mean
    assert matches[0].any() and matches[1].any()


def test_refusals_are_one_line_usage_errors():
    model = MMVAE(("traj", "image"))
    with pytest.raises(UsageError, match=r"mmvae cannot encode inputs \{label\}"):
        model.encode(make_batch(2, modalities=("label",)))
    with pytest.raises(UsageError, match="mmvae cannot generate 'label'"):
        model.generate(make_batch(2, modalities=("traj",)), "label")
    with pytest.raises(UsageError, match=r"mmvae cannot estimate log p\(x_I \| x_TI\)"):
        model.importance_path(
            "image", torch.zeros(2, 1, 28, 28), make_batch(2, modalities=("traj", "image"))
        )
    with pytest.raises(ValueError, match="k must be an integer >= 1"):
        MMVAE(k=0)
