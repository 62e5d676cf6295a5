"""Tests of ``prg.models.mvae``: the product of experts with the prior expert, the subsampled
ELBO against a hand computation (during the KL warm-up too), training on the small dataset, and the interface over every
input subset."""

from __future__ import annotations

from itertools import combinations

import numpy as np
import pytest
import torch

from prg.errors import UsageError
from prg.evaluation.likelihood import iw_log_likelihood
from prg.models.mvae import MVAE
from tests.helpers.baselines import (
    FixedExpert,
    gauss_logpdf,
    kl_std_normal,
    label_logp,
    linear_decoder,
    loss_falls,
    poe,
    small_batches,
    traj_logp,
    weights_of,
)
from tests.helpers.models import ALL, make_batch

SUBSETS = [s for r in (1, 2, 3) for s in combinations(ALL, r)]

# two samples, latent 2: the experts' outputs
MU_T, LV_T = [[0.5, -1.0], [0.2, 0.3]], [[-0.5, 0.2], [0.1, -1.0]]
MU_S, LV_S = [[-0.3, 0.8], [1.0, 0.0]], [[0.3, -0.7], [-0.2, 0.4]]
EPS = {  # the noise of each ELBO term, in the order joint, T, S
    "TS": np.array([[0.3, -1.2], [0.7, 0.1]]),
    "T": np.array([[-0.4, 0.9], [1.5, -0.6]]),
    "S": np.array([[0.2, 0.2], [-1.1, 0.8]]),
}


def tiny_mvae(**kwargs) -> MVAE:
    torch.manual_seed(0)
    model = MVAE(("traj", "label"), latent_dim=2, **kwargs)
    model.experts["traj"] = FixedExpert(MU_T, LV_T)
    model.experts["label"] = FixedExpert(MU_S, LV_S)
    model.decoders["traj"] = linear_decoder(2, 200, seed=1)
    model.decoders["label"] = linear_decoder(2, 62, seed=2)
    noise = [torch.tensor(EPS[k], dtype=torch.float32) for k in ("TS", "T", "S")]
    model.noise = lambda like: noise.pop(0)
    return model


def test_encode_is_the_precision_weighted_product_with_the_prior_expert():
    model = tiny_mvae()
    q = model.encode({"traj": torch.zeros(2, 200), "label": torch.zeros(2, dtype=torch.long)})
    mean, var = poe([np.array(MU_T), np.array(MU_S)], [np.exp(LV_T), np.exp(LV_S)], prior=True)
    np.testing.assert_allclose(q.mu.detach().numpy(), mean, rtol=1e-5)
    np.testing.assert_allclose(q.logvar.exp().detach().numpy(), var, rtol=1e-5)
    # one expert: still shrunk toward 0 by the prior expert
    q_t = model.encode({"traj": torch.zeros(2, 200)})
    np.testing.assert_allclose(
        q_t.mu.detach().numpy(), np.array(MU_T) / np.exp(LV_T) / (1 / np.exp(LV_T) + 1), rtol=1e-5
    )


def test_a_bounded_expert_keeps_its_weight_in_the_product():
    # each expert's log-variance through b - softplus(b - logvar), b = 0, before the product
    model = tiny_mvae(max_expert_logvar=0.0)
    model.experts["label"] = FixedExpert(MU_S, [[30.0, -2.0], [0.5, 0.0]])  # one silent expert
    q = model.encode({"traj": torch.zeros(2, 200), "label": torch.zeros(2, dtype=torch.long)})
    lv_s = -np.log1p(np.exp(-np.array([[30.0, -2.0], [0.5, 0.0]])))  # 0 - softplus(0 - lv)
    lv_t = -np.log1p(np.exp(-np.array(LV_T)))
    mean, var = poe([np.array(MU_T), np.array(MU_S)], [np.exp(lv_t), np.exp(lv_s)], prior=True)
    np.testing.assert_allclose(q.mu.detach().numpy(), mean, rtol=1e-5)
    np.testing.assert_allclose(q.logvar.exp().detach().numpy(), var, rtol=1e-5)


@pytest.mark.parametrize("kl_scale", [1.0, 0.3])  # 0.3: part-way through the KL warm-up
def test_loss_is_the_sum_of_the_joint_and_single_elbos_computed_by_hand(kl_scale):
    model = tiny_mvae(weights={"traj": 2.0, "label": 50.0}, beta=0.5)
    model.kl_scale = kl_scale
    g = torch.Generator().manual_seed(3)
    batch = {"traj": torch.randn(2, 200, generator=g) * 0.3, "label": torch.tensor([4, 17])}
    terms = model.elbo(batch)

    x, y = batch["traj"].double().numpy(), batch["label"].numpy()
    (w_t, b_t), (w_s, b_s) = weights_of(model.decoders["traj"]), weights_of(model.decoders["label"])
    experts = {"T": (np.array(MU_T), np.exp(LV_T)), "S": (np.array(MU_S), np.exp(LV_S))}
    total = 0.0
    for name in ("TS", "T", "S"):
        mean, var = poe([experts[c][0] for c in name], [experts[c][1] for c in name], prior=True)
        z = mean + np.sqrt(var) * EPS[name]
        nelbo = 0.5 * kl_scale * kl_std_normal(mean, var)
        if "T" in name:
            nelbo = nelbo - 2.0 * traj_logp(z @ w_t.T + b_t, x)
        if "S" in name:
            nelbo = nelbo - 50.0 * label_logp(z @ w_s.T + b_s, y)
        assert terms[f"nelbo_{name}"].item() == pytest.approx(nelbo.mean(), rel=1e-4)
        total += nelbo.mean()
    assert terms["loss"].item() == pytest.approx(total, rel=1e-4)


def test_random_subsets_are_drawn_among_the_pairs():
    model = MVAE(random_subsets=3)
    torch.manual_seed(0)
    subsets = model.training_subsets()
    assert subsets[:4] == [ALL, ("traj",), ("label",), ("image",)]
    assert len(subsets) == 7 and all(len(s) == 2 for s in subsets[4:])
    assert MVAE(("traj", "label"), random_subsets=3).training_subsets() == [
        ("traj", "label"),
        ("traj",),
        ("label",),
    ]  # two modalities: no subset between the joint and the singles
    with pytest.raises(ValueError, match="random_subsets must be an integer >= 0"):
        MVAE(random_subsets=-1)


def test_mvae_trains_on_the_small_dataset(small_dataset):
    torch.manual_seed(0)
    first, last = loss_falls(MVAE(random_subsets=1), small_batches(small_dataset))
    print(f"mvae loss {first:.0f} -> {last:.0f}")
    assert last < 0.7 * first


@pytest.mark.parametrize("subset", SUBSETS, ids=lambda s: "+".join(s))
def test_every_subset_encodes_generates_and_proposes(subset):
    torch.manual_seed(0)
    model = MVAE().eval()
    inputs = make_batch(3, modalities=subset)
    q = model.encode(inputs)
    assert q.mu.shape == q.logvar.shape == (3, 16)
    for target in ALL:
        out = model.generate(inputs, target, n=2)
        assert torch.equal(out[0], out[1])  # temperature 0: the posterior mean
        assert torch.isfinite(model.generate(inputs, target, n=2, temperature=1.0)).all()
        if target not in subset:
            x = make_batch(3, modalities=(target,))[target]
            path = model.importance_path(target, x, inputs)
            estimate = iw_log_likelihood(path, x, model.likelihoods, k=4)
            assert estimate.shape == (3,) and torch.isfinite(estimate).all()


def test_marginal_proposal_is_the_single_modality_posterior():
    torch.manual_seed(0)
    model = MVAE().eval()
    x = make_batch(3, modalities=("image",))["image"]
    path = model.importance_path("image", x, {})
    q = model.encode({"image": x})
    torch.testing.assert_close(path.proposal.mu, q.mu)
    z = torch.randn(5, 3, 16)
    np.testing.assert_allclose(
        path.proposal.log_prob(z).detach().numpy(),
        gauss_logpdf(*(t.detach().double().numpy() for t in (z, q.mu, q.logvar.exp()))),
        rtol=1e-5,
    )


def test_refusals_are_one_line_usage_errors():
    model = MVAE(("traj", "label"))
    with pytest.raises(UsageError, match=r"mvae cannot encode inputs \{nothing\}"):
        model.encode({})
    with pytest.raises(UsageError, match="mvae cannot generate 'image'"):
        model.generate(make_batch(2, modalities=("label",)), "image")
    with pytest.raises(UsageError, match=r"mvae cannot estimate log p\(x_T \| x_T\)"):
        model.importance_path("traj", torch.zeros(2, 200), {"traj": torch.zeros(2, 200)})
    with pytest.raises(ValueError, match="at least two modalities"):
        MVAE(("traj",))
