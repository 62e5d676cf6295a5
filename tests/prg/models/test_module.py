"""Tests of ``prg.models.module`` (moved from the suite on: the model families (CVAE, AVAE, MUSE),
their appendix networks and the Lightning module.

Everything runs on tiny seeded in-memory batches, except the ``fast_dev_run`` checks which use
the real :class:`~prg.data.datamodule.PRGDataModule` on the session's small prepared dataset)."""

from __future__ import annotations

import lightning as L
import pytest
import torch
from torch.utils.data import DataLoader

from prg.data.datamodule import PRGDataModule
from prg.errors import UsageError
from prg.models.components import (
    TrajectoryDecoder,
)
from prg.models.module import PRGModule
from tests.helpers.models import ALL, FAMILIES, TERMS, make_batch

ADAM = {"_target_": "torch.optim.Adam", "_partial_": True, "lr": 1e-3}


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
    module = PRGModule(FAMILIES["muse"][0], ADAM, kl_warmup_epochs=2)
    path = _fit_two_batches(module, ALL, tmp_path)
    loaded = PRGModule.load_from_checkpoint(path)
    assert 0 < module.model.kl_scale < 1
    assert loaded.model.kl_scale == pytest.approx(module.model.kl_scale)


def test_prg_module_warms_up_the_muse_top_regularisers_linearly_per_step():
    module = PRGModule(FAMILIES["muse"][0], ADAM, kl_warmup_epochs=1.5)
    batches = [make_batch(8, seed=s, modalities=ALL) for s in range(4)]
    scales = []

    class Record(L.Callback):
        def on_train_batch_end(self, trainer, pl_module, outputs, batch, batch_idx):
            scales.append(pl_module.model.kl_scale)

    trainer = _trainer(max_epochs=2, limit_val_batches=0, callbacks=[Record()])
    trainer.fit(module, DataLoader(batches, batch_size=None))
    steps = 1.5 * len(batches)  # the warm-up counts optimizer steps: 1.5 epochs of 4 batches
    assert scales == pytest.approx([min(1.0, (i + 1) / steps) for i in range(8)])


def test_kl_scale_weights_the_top_kl_and_the_subset_skl():
    torch.manual_seed(0)
    model = PRGModule(FAMILIES["muse"][0], ADAM).model
    batch = make_batch(8, seed=1, modalities=ALL)

    def loss_at(scale):
        model.kl_scale = scale
        torch.manual_seed(2)
        return model.elbo(batch)

    full, none = loss_at(1.0), loss_at(0.0)
    regularisers = model.beta * full["top_kl"] + model.delta * full["subset_skl"]
    # the losses are large sums: compare the difference to within their float32 rounding
    tolerance = 1e-6 * float(full["loss"].abs())
    torch.testing.assert_close(full["loss"] - none["loss"], regularisers, atol=tolerance, rtol=0)


@pytest.mark.parametrize("bad", [-1, "two", True])
def test_prg_module_refuses_a_bad_warm_up(bad):
    with pytest.raises(UsageError, match="kl_warmup_epochs must be a number >= 0"):
        PRGModule(FAMILIES["cvae"][0], ADAM, kl_warmup_epochs=bad)


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
