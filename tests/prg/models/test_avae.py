"""Tests of ``prg.models.avae`` (moved from the suite on: the model families (CVAE, AVAE, MUSE),
their appendix networks and the Lightning module.

Everything runs on tiny seeded in-memory batches, except the ``fast_dev_run`` checks which use
the real :class:`~prg.data.datamodule.PRGDataModule` on the session's small prepared dataset)."""

from __future__ import annotations

import math
from itertools import combinations

import numpy as np
import pytest
import torch
from torch.distributions import Normal, kl_divergence

from prg.errors import UsageError
from prg.models.fusion import product_of_experts
from tests.helpers.models import ALL, FAMILIES, TERMS, make_batch, make_model


@pytest.fixture(autouse=True)
def one_thread():
    """Tiny networks gain nothing from threads, and oversubscribed cores (a training running
    beside the tests) slow multi-threaded steps down by an order of magnitude."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


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
    model.kl_scale = 0.4
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
