"""Tests of ``prg.models.muse`` (moved from the suite on: the model families (CVAE, AVAE, MUSE),
their appendix networks and the Lightning module.

Everything runs on tiny seeded in-memory batches, except the ``fast_dev_run`` checks which use
the real :class:`~prg.data.datamodule.PRGDataModule` on the session's small prepared dataset)."""

from __future__ import annotations

import pytest
import torch

from prg.errors import UsageError
from prg.models.avae import AVAE
from prg.models.muse import MUSE, proper_subsets
from tests.helpers.models import ALL, linear_sizes


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
