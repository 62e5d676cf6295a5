"""Tests of ``prg.models.components`` (moved from the suite on: the model families (CVAE, AVAE,
MUSE), their appendix networks and the Lightning module.

Everything runs on tiny seeded in-memory batches, except the ``fast_dev_run`` checks which use
the real :class:`~prg.data.datamodule.PRGDataModule` on the session's small prepared dataset)."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from torch import nn

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
from tests.helpers.models import linear_sizes, make_model


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
