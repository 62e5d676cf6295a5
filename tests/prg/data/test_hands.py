"""Tests of ``prg.data.hands`` (moved from the suite on: writers' hands: the bank a checkpoint
keeps, choosing and matching a hand, drawing letters)."""

from __future__ import annotations

import numpy as np
import torch

from prg.data.hands import HandBank
from prg.pipeline.hands import (
    hand_distances,
)
from tests.conftest import stand_in_hands


def _split(n_writers: int = 3, augmented_per_writer: int = 5, seed: int = 1) -> dict:
    bank = stand_in_hands(n_writers, seed)
    n = len(bank)
    rng = np.random.default_rng(seed)
    extra = rng.integers(n, size=augmented_per_writer * n_writers)
    return {
        "traj": np.concatenate([bank.traj, bank.traj[extra] + 0.01]),
        "label": np.concatenate([bank.label, bank.label[extra]]),
        "writer": np.array([f"w{i}" for i in np.concatenate([bank.writer, bank.writer[extra]])]),
        "augmented": np.r_[np.zeros(n, bool), np.ones(len(extra), bool)],
    }


def test_bank_keeps_only_the_original_letters():
    arrays = _split()
    bank = HandBank.from_split(arrays)
    assert len(bank) == int((~arrays["augmented"]).sum())
    np.testing.assert_array_equal(bank.traj, arrays["traj"][~arrays["augmented"]])
    assert bank.writers == ("w0", "w1", "w2")
    assert [bank.writers[i] for i in bank.writer] == list(arrays["writer"][~arrays["augmented"]])


def test_bank_survives_a_weights_only_checkpoint(tmp_path):
    bank = stand_in_hands()
    torch.save({"hands": bank.to_checkpoint()}, tmp_path / "c.ckpt")
    back = HandBank.from_checkpoint(torch.load(tmp_path / "c.ckpt", weights_only=True)["hands"])
    np.testing.assert_array_equal(back.traj, bank.traj)
    np.testing.assert_array_equal(back.label, bank.label)
    np.testing.assert_array_equal(back.writer, bank.writer)
    assert back.writers == bank.writers


def test_a_writer_without_the_given_classes_is_never_matched():
    bank = stand_in_hands(n_writers=2)
    keep = ~((bank.writer == 0) & (bank.label == 3))
    bank = HandBank(bank.traj[keep], bank.label[keep], bank.writer[keep], bank.writers)
    distances, transforms = hand_distances(bank, bank.traj[bank.label == 3][:1], np.array([3]))
    assert np.isinf(distances[0]) and np.isfinite(distances[1])
    np.testing.assert_array_equal(transforms[0], np.eye(2))
