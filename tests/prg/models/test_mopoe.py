"""Tests of ``prg.models.mopoe``: the mixture over subsets of products of experts, the
objective against a hand computation, training on the small dataset, and the interface over
every input subset."""

from __future__ import annotations

from itertools import combinations

import numpy as np
import pytest
import torch

from prg.errors import UsageError
from prg.evaluation.likelihood import iw_log_likelihood
from prg.models.base import Gaussian
from prg.models.mixture import Mixture
from prg.models.mopoe import MoPoE, stratified_assignment
from tests.helpers.baselines import (
    FixedExpert,
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

# three samples (one per subset of {T, S}), latent 2
MU_T, LV_T = [[0.5, -1.0], [0.2, 0.3], [1.0, 0.1]], [[-0.5, 0.2], [0.1, -1.0], [0.0, 0.3]]
MU_S, LV_S = [[-0.3, 0.8], [1.0, 0.0], [-0.6, -0.2]], [[0.3, -0.7], [-0.2, 0.4], [0.5, -0.1]]
EPS = np.array([[0.3, -1.2], [0.7, 0.1], [-0.5, 0.9]])


def tiny_mopoe(**kwargs) -> MoPoE:
    torch.manual_seed(0)
    model = MoPoE(("traj", "label"), latent_dim=2, **kwargs)
    model.experts["traj"] = FixedExpert(MU_T, LV_T)
    model.experts["label"] = FixedExpert(MU_S, LV_S)
    model.decoders["traj"] = linear_decoder(2, 200, seed=1)
    model.decoders["label"] = linear_decoder(2, 62, seed=2)
    model.noise = lambda like: torch.tensor(EPS, dtype=torch.float32)
    model.offset = lambda: 0  # rows 0, 1, 2 -> subsets {T}, {S}, {T, S}
    return model


def test_loss_is_reconstruction_from_one_subset_per_row_plus_the_mean_kl_by_hand():
    model = tiny_mopoe(weights={"traj": 1.0, "label": 50.0}, beta=0.7)
    g = torch.Generator().manual_seed(3)
    batch = {"traj": torch.randn(3, 200, generator=g) * 0.3, "label": torch.tensor([4, 17, 60])}
    terms = model.elbo(batch)

    x, y = batch["traj"].double().numpy(), batch["label"].numpy()
    (w_t, b_t), (w_s, b_s) = weights_of(model.decoders["traj"]), weights_of(model.decoders["label"])
    t, s = (np.array(MU_T), np.exp(LV_T)), (np.array(MU_S), np.exp(LV_S))
    subsets = [t, s, poe([t[0], s[0]], [t[1], s[1]], prior=False)]  # no prior expert
    z = np.stack([subsets[i][0][i] + np.sqrt(subsets[i][1][i]) * EPS[i] for i in range(3)])
    rec_t = -traj_logp(z @ w_t.T + b_t, x)
    rec_s = -label_logp(z @ w_s.T + b_s, y)
    kl = np.mean([kl_std_normal(m, v) for m, v in subsets], axis=0)  # (B,)
    assert terms["rec_traj"].item() == pytest.approx(rec_t.mean(), rel=1e-4)
    assert terms["rec_label"].item() == pytest.approx(rec_s.mean(), rel=1e-4)
    assert terms["kl"].item() == pytest.approx(kl.mean(), rel=1e-4)
    expected = (rec_t + 50.0 * rec_s + 0.7 * kl).mean()
    assert terms["loss"].item() == pytest.approx(expected, rel=1e-4)


def test_stratified_assignment_deals_every_subset_in_turn():
    assert stratified_assignment(7, 3, 2).tolist() == [2, 0, 1, 2, 0, 1, 2]
    counts = np.bincount(stratified_assignment(128, 7, 5).numpy(), minlength=7)
    assert counts.max() - counts.min() <= 1


def test_encode_is_the_mixture_over_the_given_subsets_products():
    model = tiny_mopoe()
    q = model.encode({"traj": torch.zeros(3, 200), "label": torch.zeros(3, dtype=torch.long)})
    assert isinstance(q, Mixture) and len(q.components) == 3
    mean, var = poe([np.array(MU_T), np.array(MU_S)], [np.exp(LV_T), np.exp(LV_S)], prior=False)
    np.testing.assert_allclose(q.components[2].mu.detach().numpy(), mean, rtol=1e-5)
    np.testing.assert_allclose(q.components[2].logvar.exp().detach().numpy(), var, rtol=1e-5)
    np.testing.assert_allclose(q.components[0].mu.detach().numpy(), MU_T, rtol=1e-6)
    single = model.encode({"label": torch.zeros(3, dtype=torch.long)})
    assert isinstance(single, Gaussian)
    np.testing.assert_allclose(single.logvar.detach().numpy(), LV_S, rtol=1e-5)


def test_mopoe_trains_on_the_small_dataset(small_dataset):
    torch.manual_seed(0)
    first, last = loss_falls(MoPoE(), small_batches(small_dataset))
    print(f"mopoe loss {first:.0f} -> {last:.0f}")
    assert last < 0.7 * first


@pytest.mark.parametrize("subset", SUBSETS, ids=lambda s: "+".join(s))
def test_every_subset_encodes_generates_and_proposes(subset):
    torch.manual_seed(0)
    model = MoPoE().eval()
    inputs = make_batch(3, modalities=subset)
    q = model.encode(inputs)
    assert len(getattr(q, "components", [q])) == 2 ** len(subset) - 1
    for target in ALL:
        out = model.generate(inputs, target, n=3, temperature=0.5)
        assert out.shape[:2] == (3, 3) and torch.isfinite(out).all()
        if target not in subset:
            x = make_batch(3, modalities=(target,))[target]
            path = model.importance_path(target, x, inputs)
            estimate = iw_log_likelihood(path, x, model.likelihoods, k=4)
            assert estimate.shape == (3,) and torch.isfinite(estimate).all()


def test_refusals_are_one_line_usage_errors():
    model = MoPoE()
    with pytest.raises(UsageError, match=r"mopoe cannot encode inputs \{nothing\}"):
        model.encode({})
    with pytest.raises(UsageError, match="mopoe cannot generate 'speech'"):
        model.generate(make_batch(2, modalities=("traj",)), "speech")
    with pytest.raises(UsageError, match=r"mopoe cannot estimate log p\(x_S \| x_TS\)"):
        model.importance_path(
            "label", torch.zeros(2, dtype=torch.long), make_batch(2, modalities=("traj", "label"))
        )
