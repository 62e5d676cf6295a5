"""The model families (CVAE, AVAE, MUSE), their appendix networks and the Lightning module.

Everything runs on tiny seeded in-memory batches, except the ``fast_dev_run`` checks which use the
real :class:`~prg.data.datamodule.PRGDataModule` on the session's small prepared dataset.
"""

from __future__ import annotations

import math
from itertools import combinations

import lightning as L
import numpy as np
import pytest
import torch
from torch import nn
from torch.distributions import Normal, kl_divergence
from torch.utils.data import DataLoader

from prg.data.datamodule import PRGDataModule
from prg.errors import UsageError
from prg.models.avae import AVAE
from prg.models.components import (
    TRAJ_DIM,
    ImageDecoder,
    ImageEncoder,
    LabelDecoder,
    LabelEncoder,
    TrajectoryDecoder,
    TrajectoryEncoder,
    shift_images,
)
from prg.models.cvae import CVAE
from prg.models.fusion import product_of_experts
from prg.models.module import PRGModule
from prg.models.muse import MUSE, proper_subsets

ALL = ("traj", "label", "image")
FAMILIES = {
    "cvae": ({"_target_": "prg.models.cvae.CVAE"}, ("traj", "label")),
    "avae_ts": (
        {"_target_": "prg.models.avae.AVAE", "modalities": ["traj", "label"]},
        ("traj", "label"),
    ),
    "avae_ti": (
        {"_target_": "prg.models.avae.AVAE", "modalities": ["traj", "image"]},
        ("traj", "image"),
    ),
    "muse": ({"_target_": "prg.models.muse.MUSE"}, ALL),
}
ADAM = {"_target_": "torch.optim.Adam", "_partial_": True, "lr": 1e-3}


@pytest.fixture(autouse=True)
def one_thread():
    """Tiny networks gain nothing from threads, and oversubscribed cores (a training running
    beside the tests) slow multi-threaded steps down by an order of magnitude."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


def make_model(family: str, seed: int = 0, **kwargs):
    torch.manual_seed(seed)
    if family == "cvae":
        return CVAE(**kwargs)
    if family == "avae_ts":
        return AVAE(("traj", "label"), **kwargs)
    if family == "avae_ti":
        return AVAE(("traj", "image"), **kwargs)
    return MUSE(**kwargs)


def make_batch(n: int = 8, seed: int = 0, modalities=ALL) -> dict[str, torch.Tensor]:
    """Seeded fake data in the datamodule's format (trajectories of O(0.3), grey images)."""
    g = torch.Generator().manual_seed(seed)
    batch = {
        "traj": torch.randn(n, 200, generator=g) * 0.3,
        "label": torch.randint(0, 62, (n,), generator=g),
        "image": torch.rand(n, 1, 28, 28, generator=g),
    }
    return {m: batch[m] for m in modalities}


def linear_sizes(module: nn.Module) -> list[tuple[int, int]]:
    return [(m.in_features, m.out_features) for m in module.modules() if isinstance(m, nn.Linear)]


def count(module: nn.Module, kind: type) -> int:
    return sum(isinstance(m, kind) for m in module.modules())


def output_shapes(module: nn.Module, kind: type, x: torch.Tensor) -> list[tuple[int, ...]]:
    """Output shapes of every submodule of ``kind`` during one forward pass."""
    shapes: list[tuple[int, ...]] = []
    hooks = [
        m.register_forward_hook(lambda _m, _i, out: shapes.append(tuple(out.shape)))
        for m in module.modules()
        if isinstance(m, kind)
    ]
    with torch.no_grad():
        module(x)
    for h in hooks:
        h.remove()
    return shapes


# ---- appendix networks ---------------------------------------------------------------------
def test_trajectory_encoder_is_fc512x3_then_two_fc16_heads():
    enc = TrajectoryEncoder()
    assert linear_sizes(enc) == [(200, 512), (512, 512), (512, 512), (512, 16), (512, 16)]
    assert count(enc, nn.LeakyReLU) == 3
    mu, logvar = enc(torch.zeros(4, 200))
    assert mu.shape == logvar.shape == (4, 16)


def test_trajectory_decoder_is_fc512x3_then_a_linear_fc200_output():
    dec = TrajectoryDecoder()
    assert linear_sizes(dec) == [(16, 512), (512, 512), (512, 512), (512, 200)]
    assert count(dec, nn.LeakyReLU) == 3
    assert isinstance(list(dec.modules())[-1], nn.Linear)  # the mean ranges over all reals
    assert dec(torch.zeros(4, 16)).shape == (4, 200)


def test_label_encoder_is_embedding_62x256_then_fc256x2_and_fc16_heads():
    enc = LabelEncoder()
    (embed,) = [m for m in enc.modules() if isinstance(m, nn.Embedding)]
    assert (embed.num_embeddings, embed.embedding_dim) == (62, 256)
    assert linear_sizes(enc) == [(256, 256), (256, 256), (256, 16), (256, 16)]
    mu, logvar = enc(torch.arange(62))
    assert mu.shape == logvar.shape == (62, 16)


def test_label_decoder_is_fc256x3_then_fc62_logits():
    dec = LabelDecoder()
    assert linear_sizes(dec) == [(16, 256), (256, 256), (256, 256), (256, 62)]
    assert dec(torch.zeros(3, 16)).shape == (3, 62)


def test_image_encoder_convolutions_are_64_128_256_channels_flattened_to_2304():
    enc = ImageEncoder()
    convs = [m for m in enc.modules() if isinstance(m, nn.Conv2d)]
    assert [(c.in_channels, c.out_channels) for c in convs] == [(1, 64), (64, 128), (128, 256)]
    assert all(
        c.kernel_size == (4, 4) and c.stride == (2, 2) and c.padding == (1, 1) for c in convs
    )
    x = torch.zeros(2, 1, 28, 28)
    assert output_shapes(enc, nn.Conv2d, x) == [(2, 64, 14, 14), (2, 128, 7, 7), (2, 256, 3, 3)]
    assert output_shapes(enc, nn.Flatten, x) == [(2, 2304)]
    assert linear_sizes(enc) == [(2304, 512), (512, 16), (512, 16)]
    mu, logvar = enc(x)
    assert mu.shape == logvar.shape == (2, 16)


def test_image_decoder_upsamples_3_7_14_28_to_one_channel_of_logits():
    dec = ImageDecoder()
    assert linear_sizes(dec) == [(16, 512), (512, 2304)]
    deconvs = [m for m in dec.modules() if isinstance(m, nn.ConvTranspose2d)]
    assert [(d.in_channels, d.out_channels) for d in deconvs] == [(256, 128), (128, 64), (64, 1)]
    assert deconvs[0].output_padding == (1, 1)
    z = torch.zeros(2, 16)
    assert output_shapes(dec, nn.ConvTranspose2d, z) == [
        (2, 128, 7, 7),
        (2, 64, 14, 14),
        (2, 1, 28, 28),
    ]
    assert isinstance(list(dec.modules())[-1], nn.ConvTranspose2d)  # logits: no activation


def test_cvae_networks_take_the_one_hot_label_concatenated():
    model = CVAE()
    assert linear_sizes(model.encoder)[0] == (200 + 62, 512)
    assert linear_sizes(model.decoder)[0] == (16 + 62, 512)


def test_muse_top_level_is_fc512x3_experts_to_8_and_decoders_back_to_16():
    model = MUSE()
    for m in ALL:
        assert linear_sizes(model.top_experts[m]) == [
            (16, 512),
            (512, 512),
            (512, 512),
            (512, 8),
            (512, 8),
        ]
        assert linear_sizes(model.top_decoders[m]) == [
            (8, 512),
            (512, 512),
            (512, 512),
            (512, 16),
        ]


# ---- elbo ----------------------------------------------------------------------------------
TERMS = {
    "cvae": {"rec_traj", "kl", "elbo", "loss"},
    "avae_ts": {"rec_traj", "kl_traj", "rec_label", "kl_label", "skl", "loss"},
    "avae_ti": {"rec_traj", "kl_traj", "rec_image", "kl_image", "skl", "loss"},
    "muse": {f"{k}_{m}" for k in ("rec", "kl", "top_rec") for m in ALL}
    | {"top_kl", "subset_skl", "loss"},
}


@pytest.mark.parametrize("family", list(FAMILIES))
def test_elbo_returns_finite_scalar_terms_with_the_documented_names(family):
    model = make_model(family)
    terms = model.elbo(make_batch(modalities=FAMILIES[family][1]))
    assert set(terms) == TERMS[family]
    for name, value in terms.items():
        assert value.shape == (), name
        assert torch.isfinite(value), name


def test_cvae_loss_is_rec_plus_weighted_kl_and_elbo_is_minus_rec_minus_kl():
    t = make_model("cvae", kl_weight=0.25).elbo(make_batch(modalities=("traj", "label")))
    torch.testing.assert_close(t["loss"], t["rec_traj"] + 0.25 * t["kl"])
    torch.testing.assert_close(t["elbo"], -(t["rec_traj"] + t["kl"]))


def test_avae_loss_weights_each_vae_and_adds_alpha_times_the_symmetric_kl():
    model = make_model("avae_ti", alpha=3.0, weights={"traj": 2.0})
    t = model.elbo(make_batch(modalities=("traj", "image")))
    want = 2.0 * (t["rec_traj"] + t["kl_traj"]) + (t["rec_image"] + t["kl_image"]) + 3 * t["skl"]
    torch.testing.assert_close(t["loss"], want)


def test_muse_loss_combines_the_terms_with_the_paper_weights():
    model = make_model("muse")
    assert model.lambdas == {"traj": 1.0, "label": 50.0, "image": 1.0}
    assert model.alphas == dict.fromkeys(ALL, 1.0)
    assert model.gammas == dict.fromkeys(ALL, 10.0)
    assert (model.beta, model.delta, model.top_latent_dim) == (1.0, 1.0, 8)
    t = model.elbo(make_batch())
    want = sum(
        model.lambdas[m] * t[f"rec_{m}"] + t[f"kl_{m}"] + 10 * t[f"top_rec_{m}"] for m in ALL
    )
    torch.testing.assert_close(t["loss"], want + t["top_kl"] + t["subset_skl"])


def _loss_floor(model, batch) -> float:
    """The loss's value at a perfect fit with zero KL: the constants of the trajectory Gaussian
    and the entropy of grey image targets (the Bernoulli log-density's maximum), each weighted
    as the family weights its reconstruction. Every term of ``loss - floor`` is >= 0."""
    traj = 200 * math.log(model.likelihoods.traj_std * math.sqrt(2 * math.pi))
    floor = {"traj": traj}
    if "image" in batch:
        x = batch["image"].clamp(1e-6, 1 - 1e-6)
        entropy = -(x * x.log() + (1 - x) * (1 - x).log()).flatten(1).sum(-1).mean()
        floor["image"] = float(entropy)
    weights = getattr(model, "lambdas", None) or getattr(model, "weights", None) or {"traj": 1.0}
    return sum(weights[m] * f for m, f in floor.items() if m in weights)


OVERFIT = {"cvae": (150, 10.0), "avae_ts": (150, 5.0), "avae_ti": (100, 5.0), "muse": (100, 2.5)}


@pytest.mark.parametrize("family", list(OVERFIT))
def test_each_family_overfits_a_tiny_fixed_batch(family):
    """16 fixed samples, Adam lr 1e-3; the excess loss (loss minus its floor, see
    ``_loss_floor``) averaged over the last 10 steps must fall below 1/factor of its value over
    the first 5 steps. Measured (seed 0, one thread): cvae 150 steps 33.8, avae_ts 150 steps
    13.4, avae_ti 100 steps 13.8, muse 100 steps 4.2; asserted: 10, 5, 5, 2.5."""
    steps, factor = OVERFIT[family]
    model = make_model(family)
    batch = make_batch(16, seed=1, modalities=FAMILIES[family][1])
    floor = _loss_floor(model, batch)
    opt = torch.optim.Adam(model.parameters(), lr=1e-3)
    excess = []
    for _ in range(steps):
        loss = model.elbo(batch)["loss"]
        opt.zero_grad()
        loss.backward()
        opt.step()
        excess.append(loss.item() - floor)
    first, last = np.mean(excess[:5]), np.mean(excess[-10:])
    print(f"{family}: excess loss {first:.1f} -> {last:.1f}, factor {first / last:.2f}")
    assert min(excess) > -1.0  # the floor is a true lower bound (up to sampling noise)
    assert first / last > factor


# ---- encode / generate ---------------------------------------------------------------------
SUBSETS = [s for r in (1, 2, 3) for s in combinations(ALL, r)]


@pytest.mark.parametrize("subset", SUBSETS, ids=lambda s: "+".join(s))
def test_muse_encodes_every_subset_and_generates_every_modality_from_it(subset):
    model = make_model("muse").eval()
    inputs = make_batch(4, modalities=subset)
    posterior = model.encode(inputs)
    assert posterior.mu.shape == posterior.logvar.shape == (4, 8)
    out = {t: model.generate(inputs, t, n=2, temperature=1.0) for t in ALL}
    assert out["traj"].shape == (2, 4, 200)
    assert out["label"].shape == (2, 4, 62)
    assert out["image"].shape == (2, 4, 1, 28, 28)
    assert all(torch.isfinite(o).all() for o in out.values())
    torch.testing.assert_close(out["label"].sum(-1), torch.ones(2, 4))
    assert ((out["image"] >= 0) & (out["image"] <= 1)).all()


def test_muse_encode_is_the_product_of_top_experts_of_bottom_means_and_the_prior():
    model = make_model("muse")
    inputs = make_batch(4, modalities=("traj", "image"))
    experts = [model.top_experts[m](model.encoders[m](inputs[m])[0]) for m in ("traj", "image")]
    mu, logvar = product_of_experts([e[0] for e in experts], [e[1] for e in experts], True)
    q = model.encode(inputs)
    torch.testing.assert_close(q.mu, mu)
    torch.testing.assert_close(q.logvar, logvar)


@pytest.mark.parametrize("family", ["avae_ts", "avae_ti"])
def test_avae_encodes_each_single_modality(family):
    model = make_model(family)
    for m in FAMILIES[family][1]:
        q = model.encode(make_batch(3, modalities=(m,)))
        assert q.mu.shape == (3, 16)


def test_avae_refuses_two_modalities_naming_the_accepted_inputs():
    model = make_model("avae_ts")
    with pytest.raises(UsageError, match="avae_ts cannot encode") as err:
        model.encode(make_batch(3, modalities=("traj", "label")))
    accepted = str(err.value).split("accepts", 1)[1]
    assert "traj" in accepted and "label" in accepted


def test_avae_refuses_a_modality_it_does_not_model():
    with pytest.raises(UsageError, match="cannot encode"):
        make_model("avae_ts").encode(make_batch(3, modalities=("image",)))


def test_cvae_accepts_traj_with_label_and_label_alone():
    model = make_model("cvae")
    q = model.encode(make_batch(3, modalities=("traj", "label")))
    assert q.mu.shape == (3, 16)
    prior = model.encode(make_batch(3, modalities=("label",)))
    torch.testing.assert_close(prior.mu, torch.zeros(3, 16))
    torch.testing.assert_close(prior.logvar, torch.zeros(3, 16))


def test_cvae_refuses_traj_without_label():
    with pytest.raises(UsageError, match=r"cvae cannot encode .*traj.*accepts.*traj.*label.*label"):
        make_model("cvae").encode(make_batch(3, modalities=("traj",)))


def test_generate_refuses_a_target_the_family_does_not_model():
    with pytest.raises(UsageError, match="cannot generate 'image'"):
        make_model("avae_ts").generate(make_batch(2, modalities=("label",)), "image")


GENERATE_FROM = {"cvae": "label", "avae_ts": "label", "avae_ti": "image", "muse": "label"}


@pytest.mark.parametrize("family", list(GENERATE_FROM))
def test_generate_at_temperature_zero_gives_identical_samples(family):
    model = make_model(family).eval()
    out = model.generate(make_batch(3, modalities=(GENERATE_FROM[family],)), "traj", n=4)
    assert out.shape == (4, 3, 200)
    for k in range(1, 4):
        torch.testing.assert_close(out[k], out[0], rtol=0, atol=0)


@pytest.mark.parametrize("family", list(GENERATE_FROM))
def test_generate_at_temperature_one_gives_differing_samples(family):
    torch.manual_seed(0)
    model = make_model(family).eval()
    out = model.generate(make_batch(3, modalities=(GENERATE_FROM[family],)), "traj", 4, 1.0)
    for k in range(1, 4):
        assert (out[k] - out[0]).abs().max() > 1e-4


# ---- MUSE's hierarchy ------------------------------------------------------------------------
def test_muse_top_level_sends_no_gradient_into_the_bottom_vaes():
    """With every bottom weight (lambda, alpha) at 0 only the top terms remain: the bottom
    encoders and decoders must get exactly zero gradient while the top level gets some."""
    zero = dict.fromkeys(ALL, 0.0)
    model = make_model("muse", lambdas=zero, alphas=zero)
    model.elbo(make_batch())["loss"].backward()
    for name, p in [*model.encoders.named_parameters(), *model.decoders.named_parameters()]:
        assert p.grad is None or torch.count_nonzero(p.grad) == 0, name
    for part in (model.top_experts, model.top_decoders):
        assert any(p.grad is not None and p.grad.abs().sum() > 0 for p in part.parameters())


def test_muse_bottom_losses_do_train_the_bottom_encoders():
    """Counterpart of the test above: with the paper's weights the encoders get a gradient."""
    model = make_model("muse")
    model.elbo(make_batch())["loss"].backward()
    for m in ALL:
        assert any(p.grad.abs().sum() > 0 for p in model.encoders[m].parameters()), m


def test_muse_mode_seeking_is_the_distance_to_the_nearest_code_of_the_same_class():
    """The term, against a plain loop: from the label posterior's mean, each modality's top
    decoder output is compared with every same-class sample's code and the nearest counts."""
    model = make_model("muse", mode_seeking=1.0)
    g = torch.Generator().manual_seed(1)
    labels = torch.tensor([3, 3, 3, 7, 7, 9])
    codes = {m: torch.randn(6, 16, generator=g) for m in ALL}
    experts = {m: model.top_experts[m](codes[m]) for m in ALL}
    terms = {}
    total = model._mode_seeking(experts, codes, labels, terms)
    mean = product_of_experts([experts["label"][0]], [experts["label"][1]])[0]
    for m in ("traj", "image"):
        decoded = model.top_decoders[m](mean)
        nearest = [
            min(float((decoded[i] - codes[m][j]).pow(2).sum()) for j in range(6) if labels[j] == y)
            for i, y in enumerate(labels)
        ]
        assert float(terms[f"mode_{m}"]) == pytest.approx(np.mean(nearest), rel=1e-5)
    assert float(total) == pytest.approx(10 * float(terms["mode_traj"] + terms["mode_image"]))
    assert "mode_label" not in terms


def test_muse_mode_bank_keeps_the_last_codes_of_each_class_across_batches():
    """With ``mode_bank`` the nearest code is searched among the last N codes of the sample's
    class from every batch seen (a ring per class), against a plain loop over what was stored;
    the bank is not part of the checkpoint."""
    model = make_model("muse", mode_seeking=1.0, mode_bank=3)
    g = torch.Generator().manual_seed(2)
    seen = {m: {} for m in ("traj", "image")}  # class -> codes in the order they were stored
    for labels in (torch.tensor([3, 3, 7]), torch.tensor([3, 9, 3, 7])):
        codes = {m: torch.randn(len(labels), 16, generator=g) for m in ALL}
        experts = {m: model.top_experts[m](codes[m]) for m in ALL}
        for m in seen:
            for y, code in zip(labels.tolist(), codes[m], strict=True):
                seen[m].setdefault(y, []).append(code)
        terms = {}
        model._mode_seeking(experts, codes, labels, terms)
        mean = product_of_experts([experts["label"][0]], [experts["label"][1]])[0]
        for m in seen:
            decoded = model.top_decoders[m](mean)
            nearest = [
                min(float((decoded[i] - c).pow(2).sum()) for c in seen[m][y][-3:])
                for i, y in enumerate(labels.tolist())
            ]
            assert float(terms[f"mode_{m}"]) == pytest.approx(np.mean(nearest), rel=1e-5)
    filled = model.banks["traj"].filled
    assert int(filled[3].sum()) == 3 and int(filled[9].sum()) == 1
    model.eval()  # validation batches never enter the bank
    codes = {m: torch.randn(2, 16, generator=g) for m in ALL}
    experts = {m: model.top_experts[m](codes[m]) for m in ALL}
    model._mode_seeking(experts, codes, torch.tensor([11, 12]), {})
    assert not model.banks["traj"].filled[[11, 12]].any()
    assert not any("bank" in key for key in model.state_dict())


@pytest.mark.parametrize("bank", [0, 3])
def test_cvae_mode_seeking_reconstructs_the_nearest_trajectory_of_the_class_from_z_zero(bank):
    """From z = 0 and each sample's label, the squared error to the nearest trajectory of its
    class over 2 std^2: among the batch's (bank 0) or the last ``bank`` seen, against a plain
    loop; only the decoder gets its gradient, and the loss adds it at its weight."""
    model = make_model("cvae", mode_seeking=2.0, mode_bank=bank)
    g = torch.Generator().manual_seed(3)
    seen: dict[int, list] = {}
    for labels in (torch.tensor([1, 1, 4]), torch.tensor([1, 4, 1, 1, 5])):
        batch = {"traj": torch.randn(len(labels), TRAJ_DIM, generator=g), "label": labels}
        for y, x in zip(labels.tolist(), batch["traj"], strict=True):
            seen.setdefault(y, []).append(x)
        model.zero_grad()
        terms = model.elbo(batch)
        decoded = model.decode(torch.zeros(len(labels), 16), "traj", batch)
        nearest = []
        for i, y in enumerate(labels.tolist()):
            pool = (
                seen[y][-bank:]
                if bank
                else [batch["traj"][j] for j in range(len(labels)) if labels[j] == y]
            )
            nearest.append(min(float((decoded[i] - x).pow(2).sum()) for x in pool) / 0.02)
        assert float(terms["mode_traj"]) == pytest.approx(np.mean(nearest), rel=1e-5)
        torch.testing.assert_close(
            terms["loss"], terms["rec_traj"] + terms["kl"] + 2.0 * terms["mode_traj"]
        )
    terms["mode_traj"].backward()
    assert all(p.grad is None or p.grad.abs().sum() == 0 for p in model.encoder.parameters())
    assert any(p.grad.abs().sum() > 0 for p in model.decoder.parameters())
    assert not any("bank" in key for key in model.state_dict())
    before = model.bank.values.clone() if bank else None
    model.eval()
    model.elbo({"traj": torch.randn(3, TRAJ_DIM, generator=g), "label": torch.tensor([1, 4, 5])})
    if bank:  # validation batches never enter the bank
        torch.testing.assert_close(model.bank.values, before)


def test_muse_mode_seeking_trains_the_label_expert_and_top_decoders_only():
    model = make_model("muse", mode_seeking=1.0)
    batch = make_batch()
    torch.manual_seed(0)
    with_term = model.elbo(batch)
    torch.manual_seed(0)
    model.mode_seeking = 0.0
    without = model.elbo(batch)
    assert "mode_traj" not in without
    torch.testing.assert_close(
        with_term["loss"] - without["loss"],
        10 * (with_term["mode_traj"] + with_term["mode_image"]),
    )
    with_term["mode_traj"].backward()
    grads = lambda module: sum(  # noqa: E731
        float(p.grad.abs().sum()) for p in module.parameters() if p.grad is not None
    )
    assert grads(model.top_experts["label"]) > 0 and grads(model.top_decoders["traj"]) > 0
    assert grads(model.top_experts["traj"]) == grads(model.encoders) == 0


def test_proper_subsets_of_three_modalities_are_three_singletons_and_three_pairs():
    assert proper_subsets(ALL) == [
        ("traj",),
        ("label",),
        ("image",),
        ("traj", "label"),
        ("traj", "image"),
        ("label", "image"),
    ]
    assert proper_subsets(("traj", "label")) == [("traj",), ("label",)]


def test_muse_subset_matching_term_is_the_mean_skl_over_the_six_proper_subsets(monkeypatch):
    """With sampling switched off (codes = bottom means, c = top mean), ``subset_skl`` must equal
    the mean over the 6 proper subsets of SKL(q(c | z_S), q(c | z_all)), recomputed here with
    torch.distributions (a mean over 7 sets, or over the 3 singletons, would differ)."""
    monkeypatch.setattr("prg.models.muse.reparameterise", lambda mu, logvar, eps=None: mu)
    model = make_model("muse")
    batch = make_batch()
    with torch.no_grad():
        terms = model.elbo(batch)
        experts = {m: model.top_experts[m](model.encoders[m](batch[m])[0]) for m in ALL}

        def posterior(subset):
            precision = 1 + sum((-experts[m][1]).exp() for m in subset)
            mean = sum(experts[m][0] * (-experts[m][1]).exp() for m in subset) / precision
            return Normal(mean, precision.rsqrt())

        q_all = posterior(ALL)
        skls = [
            (kl_divergence(posterior(s), q_all) + kl_divergence(q_all, posterior(s))).sum(-1).mean()
            for r in (1, 2)
            for s in combinations(ALL, r)
        ]
    assert len(skls) == 6
    torch.testing.assert_close(terms["subset_skl"], torch.stack(skls).mean())


# ---- importance paths ----------------------------------------------------------------------
PATHS = [
    ("cvae", "traj", ("label",), 16),
    ("avae_ts", "traj", (), 16),
    ("avae_ts", "label", (), 16),
    ("avae_ts", "traj", ("label",), 16),
    ("avae_ti", "image", (), 16),
    ("avae_ti", "traj", ("image",), 16),
    ("muse", "traj", (), 16),
    ("muse", "image", (), 16),
    ("muse", "traj", ("label",), 8),
    ("muse", "traj", ("label", "image"), 8),
    ("muse", "image", ("traj",), 8),
]


@pytest.mark.parametrize(("family", "target", "given", "dim"), PATHS)
def test_importance_path_has_the_right_latent_dim_and_gives_finite_weights(
    family, target, given, dim
):
    torch.manual_seed(0)
    model = make_model(family).eval()
    data = make_batch(3, seed=2)
    with torch.no_grad():
        assert (target, given) in model.likelihood_cells
        path = model.importance_path(target, data[target], {m: data[m] for m in given})
        assert path.target == target
        assert path.latent_dim == dim
        assert path.proposal.mu.shape == (3, dim)
        z = path.proposal.sample(5)  # (K, B, d)
        params = path.decode(z.reshape(-1, dim))
        params = params.reshape(5, 3, *params.shape[1:])
        prior = -0.5 * (z.pow(2) + math.log(2 * math.pi)).sum(-1)
        w = (
            model.likelihoods.log_prob(target, params, data[target])
            + prior
            - path.proposal.log_prob(z)
        )
    assert w.shape == (5, 3)
    assert torch.isfinite(w).all()


@pytest.mark.parametrize(
    ("family", "target", "given"),
    [
        ("cvae", "traj", ()),
        ("cvae", "label", ("traj",)),
        ("avae_ts", "image", ()),
        ("avae_ts", "traj", ("traj",)),
        ("avae_ti", "traj", ("label",)),
        ("muse", "traj", ("traj", "label")),
    ],
)
def test_a_cell_the_family_cannot_estimate_is_refused_with_what_it_can(family, target, given):
    model = make_model(family)
    data = make_batch(2, seed=1)
    with pytest.raises(UsageError, match=f"{family} cannot estimate log p.*it estimates"):
        model.importance_path(target, data[target], {m: data[m] for m in given})


# ---- Lightning module ----------------------------------------------------------------------
def _trainer(**kwargs) -> L.Trainer:
    return L.Trainer(
        accelerator="cpu",
        devices=1,
        logger=False,
        enable_checkpointing=False,
        enable_progress_bar=False,
        enable_model_summary=False,
        **kwargs,
    )


def _fit_two_batches(module: PRGModule, modalities, tmp_path):
    """Two training steps on an in-memory loader, then ``trainer.save_checkpoint``."""
    batches = [make_batch(8, seed=s, modalities=modalities) for s in (1, 2)]
    trainer = _trainer(max_epochs=1, limit_val_batches=0)
    trainer.fit(module, DataLoader(batches, batch_size=None))
    assert trainer.global_step == 2
    path = tmp_path / "model.ckpt"
    trainer.save_checkpoint(path)
    return path


@pytest.mark.parametrize("family", ["cvae", "muse"])
def test_prg_module_round_trips_through_a_lightning_checkpoint(family, tmp_path):
    config, modalities = FAMILIES[family]
    torch.manual_seed(0)
    module = PRGModule(config, ADAM)
    path = _fit_two_batches(module, modalities, tmp_path)

    loaded = PRGModule.load_from_checkpoint(path)
    assert loaded.family == family
    module.eval()
    loaded.eval()
    for name, value in module.state_dict().items():
        torch.testing.assert_close(loaded.state_dict()[name], value, rtol=0, atol=0)
    torch.manual_seed(0)
    fresh = PRGModule(config, ADAM)
    assert any(not torch.equal(fresh.state_dict()[k], v) for k, v in module.state_dict().items()), (
        "the two training steps changed no weight"
    )

    inputs = make_batch(4, seed=3, modalities=modalities)
    given = {"label": inputs["label"]} if family == "cvae" else inputs
    torch.testing.assert_close(loaded.model.encode(given).mu, module.model.encode(given).mu)
    torch.testing.assert_close(
        loaded.model.generate(given, "traj", n=2), module.model.generate(given, "traj", n=2)
    )
    torch.manual_seed(5)
    want = module(inputs)
    torch.manual_seed(5)
    got = loaded(inputs)
    assert set(got) == set(want)
    for k in want:
        torch.testing.assert_close(got[k], want[k], msg=k)


def test_prg_module_checkpoint_keeps_the_top_warm_up_state(tmp_path):
    torch.manual_seed(0)
    module = PRGModule(FAMILIES["muse"][0], ADAM, top_warmup_epochs=2)
    path = _fit_two_batches(module, ALL, tmp_path)
    loaded = PRGModule.load_from_checkpoint(path)
    assert 0 < module.model.top_scale < 1
    assert loaded.model.top_scale == pytest.approx(module.model.top_scale)


def test_prg_module_warms_up_the_muse_top_regularisers_linearly_per_step():
    module = PRGModule(FAMILIES["muse"][0], ADAM, top_warmup_epochs=1.5)
    batches = [make_batch(8, seed=s, modalities=ALL) for s in range(4)]
    scales = []

    class Record(L.Callback):
        def on_train_batch_end(self, trainer, pl_module, outputs, batch, batch_idx):
            scales.append(pl_module.model.top_scale)

    trainer = _trainer(max_epochs=2, limit_val_batches=0, callbacks=[Record()])
    trainer.fit(module, DataLoader(batches, batch_size=None))
    steps = 1.5 * len(batches)  # the warm-up counts optimizer steps: 1.5 epochs of 4 batches
    assert scales == pytest.approx([min(1.0, (i + 1) / steps) for i in range(8)])


def test_top_scale_weights_the_top_kl_and_the_subset_skl():
    torch.manual_seed(0)
    model = PRGModule(FAMILIES["muse"][0], ADAM).model
    batch = make_batch(8, seed=1, modalities=ALL)

    def loss_at(scale):
        model.top_scale = scale
        torch.manual_seed(2)
        return model.elbo(batch)

    full, none = loss_at(1.0), loss_at(0.0)
    regularisers = model.beta * full["top_kl"] + model.delta * full["subset_skl"]
    # the losses are large sums: compare the difference to within their float32 rounding
    tolerance = 1e-6 * float(full["loss"].abs())
    torch.testing.assert_close(full["loss"] - none["loss"], regularisers, atol=tolerance, rtol=0)


@pytest.mark.parametrize("bad", [-1, "two", True])
def test_prg_module_refuses_a_bad_warm_up(bad):
    with pytest.raises(UsageError, match="top_warmup_epochs must be a number >= 0"):
        PRGModule(FAMILIES["cvae"][0], ADAM, top_warmup_epochs=bad)


def test_one_cycle_schedule_spans_the_run_and_steps_per_batch():
    schedule = {
        "_target_": "torch.optim.lr_scheduler.OneCycleLR",
        "_partial_": True,
        "max_lr": 1e-3,
        "pct_start": 0.25,
    }
    module = PRGModule(FAMILIES["cvae"][0], ADAM, scheduler=schedule)
    batches = [make_batch(8, seed=s, modalities=("traj", "label")) for s in range(4)]
    rates = []

    class Record(L.Callback):
        def on_train_batch_start(self, trainer, pl_module, batch, batch_idx):
            rates.append(trainer.optimizers[0].param_groups[0]["lr"])

    trainer = _trainer(max_epochs=2, limit_val_batches=0, callbacks=[Record()])
    trainer.fit(module, DataLoader(batches, batch_size=None))
    assert len(rates) == 8
    peak = rates.index(max(rates))
    assert max(rates) == pytest.approx(1e-3)
    assert rates[0] < max(rates) / 10 and 0 < peak < 4  # warms up in the first quarter ...
    assert all(a >= b for a, b in zip(rates[peak:], rates[peak + 1 :]))  # ... then only falls
    assert rates[-1] < rates[0]  # to below its starting value by the run's last step


def test_zero_init_trajectory_starts_every_trajectory_decoder_flat():
    for family in FAMILIES:
        module = PRGModule(FAMILIES[family][0], ADAM, zero_init_trajectory=True)
        decoders = [m for m in module.model.modules() if isinstance(m, TrajectoryDecoder)]
        assert decoders, family
        z = torch.randn(5, decoders[0].net[0].in_features)
        for decoder in decoders:
            assert torch.count_nonzero(decoder(z)) == 0, family
        default = PRGModule(FAMILIES[family][0], ADAM)
        other = next(m for m in default.model.modules() if isinstance(m, TrajectoryDecoder))
        assert torch.count_nonzero(other(z)) > 0, family


def test_shift_images_moves_each_image_by_its_own_offset_within_the_bound():
    images = torch.zeros(300, 1, 28, 28)
    images[:, 0, 14, 14] = 1.0
    torch.manual_seed(0)
    shifted = shift_images(images, 2)
    assert shifted.shape == images.shape
    assert torch.equal(shifted.sum((1, 2, 3)), torch.ones(300))  # the ink is moved, not lost
    rows, cols = shifted[:, 0].nonzero()[:, 1], shifted[:, 0].nonzero()[:, 2]
    offsets = set(zip((rows - 14).tolist(), (cols - 14).tolist()))
    assert offsets == {(dy, dx) for dy in range(-2, 3) for dx in range(-2, 3)}
    assert shift_images(images, 0) is images


def test_shift_images_fills_the_uncovered_border_with_background():
    images = torch.ones(50, 1, 28, 28)
    torch.manual_seed(1)
    shifted = shift_images(images, 3)
    uncovered = (shifted == 0).sum((1, 2, 3))
    assert uncovered.max() > 0 and uncovered.max() <= 28 * 28 - 25 * 25
    assert set(shifted.unique().tolist()) <= {0.0, 1.0}


@pytest.mark.parametrize("family", ["avae_ti", "muse"])
def test_elbo_encodes_the_given_inputs_and_reconstructs_the_batch(family):
    model = make_model(family)
    modalities = FAMILIES[family][1]
    batch = make_batch(6, seed=2, modalities=modalities)
    inputs = {**batch, "image": make_batch(6, seed=3)["image"]}

    def terms(*args):
        torch.manual_seed(4)
        with torch.no_grad():
            return model.elbo(*args)

    denoising, on_inputs, on_batch = terms(batch, inputs), terms(inputs), terms(batch)
    _close(denoising["kl_image"], on_inputs["kl_image"], "the encoder sees the inputs")
    assert not torch.isclose(denoising["kl_image"], on_batch["kl_image"])
    assert not torch.isclose(denoising["rec_image"], on_inputs["rec_image"])  # other targets
    _close(denoising["rec_traj"], on_inputs["rec_traj"], "other modalities are unchanged")


def test_prg_module_shifts_the_encoders_images_in_training_steps_only(monkeypatch):
    module = PRGModule(FAMILIES["muse"][0], ADAM, image_shift=2)
    seen = []
    elbo = module.model.elbo
    monkeypatch.setattr(
        module.model, "elbo", lambda batch, inputs=None: seen.append(inputs) or elbo(batch, inputs)
    )
    monkeypatch.setattr(module, "log", lambda *a, **k: None)
    batch = make_batch(8, seed=6)
    original = batch["image"].clone()
    module.training_step(batch, 0)
    module.validation_step(batch, 0)
    assert torch.equal(batch["image"], original)  # the targets stay the unshifted images
    assert not torch.equal(seen[0]["image"], original)
    assert torch.equal(seen[0]["traj"], batch["traj"])
    assert seen[1] is None  # validation scores the images as they are
    unshifted = PRGModule(FAMILIES["muse"][0], ADAM)
    monkeypatch.setattr(
        unshifted.model, "elbo", lambda b, inputs=None: seen.append(inputs) or elbo(b)
    )
    unshifted.training_step(batch, 0)
    assert seen[2] is None


@pytest.mark.parametrize("bad", [-1, 1.5, True, "2"])
def test_prg_module_refuses_a_bad_image_shift(bad):
    with pytest.raises(UsageError, match="image_shift must be a whole number of pixels"):
        PRGModule(FAMILIES["muse"][0], ADAM, image_shift=bad)


@pytest.mark.parametrize("family", list(FAMILIES))
def test_fast_dev_run_on_the_prepared_dataset(family, small_dataset):
    config, modalities = FAMILIES[family]
    torch.manual_seed(0)
    module = PRGModule(config, ADAM)
    dm = PRGDataModule(small_dataset, "synthetic", modalities=modalities, batch_size=16)
    trainer = _trainer(fast_dev_run=2)
    trainer.fit(module, datamodule=dm)
    assert trainer.state.finished
    assert trainer.global_step == 2
    metrics = trainer.callback_metrics
    for split in ("train", "val"):
        assert torch.isfinite(metrics[f"{split}/loss"]), split
    assert {k for k in metrics if k.startswith("train/")} == {f"train/{t}" for t in TERMS[family]}


def test_imputing_moves_a_label_posterior_and_only_muse_imputes():
    torch.manual_seed(0)
    muse = MUSE().eval()
    labels = torch.arange(5)
    with torch.no_grad():
        plain = muse.encode({"label": labels})
        assert torch.equal(muse.encode_imputed({"label": labels}, 0).mu, plain.mu)
        once = muse.encode_imputed({"label": labels}, 1)
        # by hand: decode the missing trajectory and image from the plain mean, encode them,
        # fuse them with the label's expert
        traj = muse.decode(plain.mu, "traj")
        image = muse.decode(plain.mu, "image").sigmoid()
        codes = {
            "label": muse.encoders["label"](labels)[0],
            "traj": muse.encoders["traj"](traj)[0],
            "image": muse.encoders["image"](image)[0],
        }
        expected = muse.top_posterior(codes)
        assert torch.allclose(once.mu, expected.mu, atol=1e-5)
        assert torch.allclose(once.logvar, expected.logvar, atol=1e-5)
        assert not torch.allclose(once.mu, plain.mu)
        generated = muse.generate({"label": labels}, "traj", impute_steps=1)[0]
        assert torch.allclose(generated, muse.decode(once.mu, "traj"), atol=1e-5)
    assert MUSE.imputes_missing and not AVAE(("traj", "label")).imputes_missing
    avae = AVAE(("traj", "label")).eval()
    assert torch.equal(
        avae.generate({"label": labels}, "traj", impute_steps=3),
        avae.generate({"label": labels}, "traj"),
    )
    for bad in (-1, 1.5, True):
        with pytest.raises(UsageError, match="impute_steps must be an integer >= 0"):
            muse.generate({"label": labels}, "traj", impute_steps=bad)


# ---- every field of a posterior, and the variance in use ---------------------------------------
# A test that looks at a posterior's mean (or only at its shape) cannot see a log-variance that is
# dropped or replaced. These compare every returned field against the networks' own outputs and
# every loss term against torch.distributions, replaying the model's random draws with the same
# seed (the latent noise is drawn with torch.randn_like, in the order the terms are computed).


def _normal(mu: torch.Tensor, logvar: torch.Tensor) -> Normal:
    return Normal(mu, (0.5 * logvar).exp())


def _kl_prior(mu: torch.Tensor, logvar: torch.Tensor) -> torch.Tensor:
    return kl_divergence(_normal(mu, logvar), Normal(0.0, 1.0)).sum(-1)


def _sym_kl(a: tuple, b: tuple) -> torch.Tensor:
    qa, qb = _normal(*a), _normal(*b)
    return (kl_divergence(qa, qb) + kl_divergence(qb, qa)).sum(-1)


def _product(experts: list[tuple[torch.Tensor, torch.Tensor]]) -> tuple[torch.Tensor, torch.Tensor]:
    """Product of the experts and N(0, I), folded pairwise in variance form (not the code's
    precision form): var = v1 v2 / (v1 + v2), mean = (m1 v2 + m2 v1) / (v1 + v2)."""
    mean, var = torch.zeros_like(experts[0][0]), torch.ones_like(experts[0][0])
    for m2, lv2 in experts:
        v2 = lv2.exp()
        mean, var = (mean * v2 + m2 * var) / (var + v2), var * v2 / (var + v2)
    return mean, var.log()


def _log_lik(modality: str, params: torch.Tensor, x: torch.Tensor, std: float) -> torch.Tensor:
    if modality == "traj":
        return Normal(params, std).log_prob(x).sum(-1)
    if modality == "label":
        return torch.distributions.Categorical(logits=params).log_prob(x)
    bern = torch.distributions.Bernoulli(logits=params, validate_args=False)
    return bern.log_prob(x).flatten(1).sum(-1)


def _close(got: torch.Tensor, want: torch.Tensor, name: str) -> None:
    torch.testing.assert_close(got, want, rtol=1e-4, atol=1e-4, msg=name)


@pytest.mark.parametrize("family", ["avae_ts", "avae_ti"])
def test_avae_encode_returns_the_whole_posterior_of_the_given_modality(family):
    model = make_model(family)
    for m in FAMILIES[family][1]:
        x = make_batch(5, seed=3, modalities=(m,))[m]
        mu, logvar = model.encoders[m](x)
        q = model.encode({m: x})
        torch.testing.assert_close(q.mu, mu, rtol=0, atol=0)
        torch.testing.assert_close(q.logvar, logvar, rtol=0, atol=0)
        assert logvar.std() > 1e-3  # a real, input-dependent variance


def test_cvae_encode_returns_the_whole_posterior_of_trajectory_and_label():
    model = make_model("cvae")
    batch = make_batch(5, seed=3, modalities=("traj", "label"))
    onehot = torch.nn.functional.one_hot(batch["label"], 62).float()
    mu, logvar = model.encoder(torch.cat([batch["traj"], onehot], -1))
    q = model.encode(batch)
    torch.testing.assert_close(q.mu, mu, rtol=0, atol=0)
    torch.testing.assert_close(q.logvar, logvar, rtol=0, atol=0)


@pytest.mark.parametrize(("family", "target", "given", "dim"), PATHS)
def test_importance_path_proposal_is_the_whole_posterior(family, target, given, dim):
    model = make_model(family).eval()
    data = make_batch(3, seed=2)
    with torch.no_grad():
        path = model.importance_path(target, data[target], {m: data[m] for m in given})
        if family == "cvae":
            want = model.encode({"traj": data["traj"], "label": data["label"]})
            want = (want.mu, want.logvar)
        elif not given:  # the marginal: the target's own (bottom) encoder
            want = model.encoders[target](data[target])
        else:
            q = model.encode({m: data[m] for m in given})
            want = (q.mu, q.logvar)
    torch.testing.assert_close(path.proposal.mu, want[0], rtol=0, atol=0)
    torch.testing.assert_close(path.proposal.logvar, want[1], rtol=0, atol=0)


@pytest.mark.parametrize("family", list(GENERATE_FROM))
@pytest.mark.parametrize("temperature", [1.0, 0.4])
def test_generate_draws_latents_with_the_posterior_spread_times_temperature(family, temperature):
    model = make_model(family).eval()
    with torch.no_grad():  # untrained heads give logvar ~ 0, which hides a dropped variance
        for name, module in model.named_modules():
            if name.endswith("logvar"):
                module.bias.fill_(-2.0)
    source = GENERATE_FROM[family]
    inputs = make_batch(3, seed=4, modalities=(source,))
    if family != "cvae":  # the CVAE's label-only posterior is the prior N(0, I)
        assert model.encode(inputs).logvar.max() < -1.0
    torch.manual_seed(11)
    out = model.generate(inputs, "traj", n=5, temperature=temperature)
    with torch.no_grad():
        q = model.encode(inputs)
        torch.manual_seed(11)
        eps = torch.randn((5, *q.mu.shape))
        z = q.mu + (0.5 * q.logvar).exp() * temperature * eps  # (5, 3, d)
        context = {source: inputs[source].repeat(5, *([1] * (inputs[source].dim() - 1)))}
        want = model.decode(z.reshape(-1, z.shape[-1]), "traj", context).reshape(5, 3, 200)
    _close(out, want, "generated trajectories")


def test_cvae_elbo_terms_match_torch_distributions():
    model = make_model("cvae", kl_weight=0.3, traj_std=0.2)
    batch = make_batch(6, seed=5, modalities=("traj", "label"))
    torch.manual_seed(7)
    terms = model.elbo(batch)
    with torch.no_grad():
        onehot = torch.nn.functional.one_hot(batch["label"], 62).float()
        mu, logvar = model.encoder(torch.cat([batch["traj"], onehot], -1))
        torch.manual_seed(7)
        z = mu + (0.5 * logvar).exp() * torch.randn_like(mu)
        params = model.decoder(torch.cat([z, onehot], -1))
        rec = -_log_lik("traj", params, batch["traj"], 0.2).mean()
        kl = _kl_prior(mu, logvar).mean()
    want = {"rec_traj": rec, "kl": kl, "loss": rec + 0.3 * kl, "elbo": -(rec + kl)}
    assert set(terms) == set(want)
    for name, value in want.items():
        _close(terms[name].detach(), value, name)


@pytest.mark.parametrize("family", ["avae_ts", "avae_ti"])
def test_avae_elbo_terms_match_torch_distributions(family):
    modalities = FAMILIES[family][1]
    weights = {modalities[0]: 0.7, modalities[1]: 1.9}
    model = make_model(family, alpha=2.5, weights=weights, traj_std=0.15)
    batch = make_batch(6, seed=5, modalities=modalities)
    torch.manual_seed(8)
    terms = model.elbo(batch)
    want: dict[str, torch.Tensor] = {}
    with torch.no_grad():
        posts = {m: model.encoders[m](batch[m]) for m in modalities}
        torch.manual_seed(8)
        eps = torch.randn_like(posts[modalities[0]][0])  # one draw shared by the two VAEs
        loss = 0.0
        for m, (mu, logvar) in posts.items():
            z = mu + (0.5 * logvar).exp() * eps
            want[f"rec_{m}"] = -_log_lik(m, model.decoders[m](z), batch[m], 0.15).mean()
            want[f"kl_{m}"] = _kl_prior(mu, logvar).mean()
            loss = loss + weights[m] * (want[f"rec_{m}"] + want[f"kl_{m}"])
        want["skl"] = _sym_kl(posts[modalities[0]], posts[modalities[1]]).mean()
        want["loss"] = loss + 2.5 * want["skl"]
    assert set(terms) == set(want)
    for name, value in want.items():
        _close(terms[name].detach(), value, name)


def test_muse_elbo_terms_match_torch_distributions_and_a_hand_product_of_experts():
    lambdas, alphas = {"traj": 2.0, "label": 7.0, "image": 0.5}, {"traj": 0.3, "label": 1.5}
    gammas = {"traj": 3.0, "label": 0.2, "image": 4.0}
    model = make_model(
        "muse", lambdas=lambdas, alphas=alphas, gammas=gammas, beta=0.6, delta=2.2, traj_std=0.3
    )
    model.top_scale = 0.4
    alphas = {**alphas, "image": 1.0}  # the default of the one left out
    batch = make_batch(6, seed=9)
    torch.manual_seed(12)
    terms = model.elbo(batch)
    want: dict[str, torch.Tensor] = {}
    with torch.no_grad():
        torch.manual_seed(12)
        loss, codes = 0.0, {}
        for m in ALL:
            mu, logvar = model.encoders[m](batch[m])
            z = mu + (0.5 * logvar).exp() * torch.randn_like(mu)
            want[f"rec_{m}"] = -_log_lik(m, model.decoders[m](z), batch[m], 0.3).mean()
            want[f"kl_{m}"] = _kl_prior(mu, logvar).mean()
            loss = loss + lambdas[m] * want[f"rec_{m}"] + alphas[m] * want[f"kl_{m}"]
            codes[m] = z
        experts = {m: model.top_experts[m](codes[m]) for m in ALL}
        q_all = _product(list(experts.values()))
        c = q_all[0] + (0.5 * q_all[1]).exp() * torch.randn_like(q_all[0])
        for m in ALL:
            want[f"top_rec_{m}"] = (model.top_decoders[m](c) - codes[m]).pow(2).sum(-1).mean()
            loss = loss + gammas[m] * want[f"top_rec_{m}"]
        want["top_kl"] = _kl_prior(*q_all).mean()
        subsets = [s for r in (1, 2) for s in combinations(ALL, r)]
        want["subset_skl"] = torch.stack(
            [_sym_kl(_product([experts[m] for m in s]), q_all).mean() for s in subsets]
        ).mean()
        want["loss"] = loss + 0.4 * (0.6 * want["top_kl"] + 2.2 * want["subset_skl"])
    assert set(terms) == set(want)
    for name, value in want.items():
        _close(terms[name].detach(), value, name)


def test_muse_posteriors_of_every_subset_are_the_hand_product_of_their_experts():
    model = make_model("muse").eval()
    batch = make_batch(4, seed=6)
    with torch.no_grad():
        for subset in SUBSETS:
            q = model.encode({m: batch[m] for m in subset})
            experts = [model.top_experts[m](model.encoders[m](batch[m])[0]) for m in subset]
            mu, logvar = _product(experts)
            _close(q.mu, mu, f"mu of {subset}")
            _close(q.logvar, logvar, f"logvar of {subset}")
