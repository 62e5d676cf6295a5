"""Tests of ``prg.pipeline.hands`` (moved from the suite on: writers' hands: the bank a checkpoint
keeps, choosing and matching a hand, drawing letters)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from prg.alphabet import NUM_CLASSES, char_to_label
from prg.data.hands import HandBank
from prg.errors import UsageError
from prg.pipeline.hands import (
    Hand,
    components,
    decode_in_hand,
    match_hand,
    random_hand,
    read_style,
)
from prg.pipeline.perceive import perceive_trajectories
from tests.conftest import letter_like, stand_in_hands


def test_a_seed_gives_one_hand_and_seeds_reach_every_writer():
    bank = stand_in_hands(n_writers=4)
    assert random_hand(bank, 7) == random_hand(bank, 7)
    assert {random_hand(bank, s).writer for s in range(60)} == {0, 1, 2, 3}


def test_a_persons_letters_are_matched_to_the_writer_who_wrote_alike():
    bank = stand_in_hands(n_writers=4)
    rng = np.random.default_rng(3)
    for writer in range(4):
        mine = np.flatnonzero(bank.writer == writer)[[5, 20, 40]]
        noisy = bank.traj[mine] + rng.normal(0, 0.01, size=bank.traj[mine].shape)
        hand = match_hand(bank, noisy, bank.label[mine])
        assert hand.writer == writer
        np.testing.assert_array_equal(hand.own_label, bank.label[mine])


def test_components_use_own_letters_then_the_writers_then_the_nearest_writers():
    bank = stand_in_hands(n_writers=3)
    # writer 1 never wrote class 9: the component comes from another writer's class 9
    keep = ~((bank.writer == 1) & (bank.label == 9))
    bank = HandBank(bank.traj[keep], bank.label[keep], bank.writer[keep], bank.writers)
    own = np.full((1, 200), 0.5, dtype=np.float32)
    hand = Hand(1, own, np.array([4]))
    labels = np.array([4, 7, 9])
    chosen = components(bank, hand, labels, seed=0)
    np.testing.assert_array_equal(chosen[0], own[0])
    np.testing.assert_array_equal(chosen[1], bank.traj[(bank.writer == 1) & (bank.label == 7)][0])
    nines = bank.traj[bank.label == 9]
    assert any(np.array_equal(chosen[2], row) for row in nines)


def test_a_class_no_writer_wrote_is_one_clear_error():
    bank = stand_in_hands(n_writers=2)
    keep = bank.label != char_to_label("q")
    bank = HandBank(bank.traj[keep], bank.label[keep], bank.writer[keep], bank.writers)
    with pytest.raises(UsageError, match=r"'q'.*never wrote"):
        components(bank, Hand(0), np.array([char_to_label("q")]), seed=0)


@pytest.fixture(scope="module")
def muse(untrained_muse_checkpoint):
    from prg.models.checkpoint import load_model

    model, info = load_model(untrained_muse_checkpoint)
    return model, info["hands"]


def test_decoding_in_a_hand_is_seeded_and_its_temperature_scales_the_variation(muse):
    model, bank = muse
    labels = np.arange(NUM_CLASSES)[:6]
    chosen = components(bank, Hand(0), labels, seed=0)
    mean = decode_in_hand(model, chosen, labels, 0.0, seed=1)
    np.testing.assert_array_equal(mean, decode_in_hand(model, chosen, labels, 0.0, seed=2))
    assert mean.shape == (6, 100, 2)
    a = decode_in_hand(model, chosen, labels, 0.5, seed=1)
    np.testing.assert_array_equal(a, decode_in_hand(model, chosen, labels, 0.5, seed=1))
    b = decode_in_hand(model, chosen, labels, 0.5, seed=2)
    assert not np.allclose(a, b)
    far = decode_in_hand(model, chosen, labels, 1.0, seed=1)
    assert np.abs(far - mean).mean() > np.abs(a - mean).mean()


def test_a_blend_of_writers_decodes_the_mean_of_their_codes(muse):
    import torch

    from prg.models.modalities import TRAJ

    model, bank = muse
    labels = np.arange(NUM_CLASSES)[:6]
    first, second = (components(bank, Hand(w), labels, seed=0) for w in (0, 1))
    alone = decode_in_hand(model, first, labels, 0.0, seed=1)
    np.testing.assert_allclose(
        decode_in_hand(model, np.stack([first, first]), labels, 0.0, 1), alone
    )
    blend = decode_in_hand(model, np.stack([first, second]), labels, 0.0, seed=1)
    with torch.no_grad():  # by hand: the two codes' mean, decoded
        codes = [model.encoders[TRAJ](torch.from_numpy(c))[0] for c in (first, second)]
        mean = model.likelihoods.mean(TRAJ, model.decoders[TRAJ]((codes[0] + codes[1]) / 2))
    np.testing.assert_allclose(blend, mean.numpy().reshape(6, 100, 2), atol=1e-6)
    assert not np.allclose(blend, alone)


def _letters(rng, n):
    return [letter_like(rng) for _ in range(n)]


def test_style_files_read_in_each_accepted_format(tmp_path):
    from prg.data.samples import RawSample
    from prg.data.uji import format_uji

    rng = np.random.default_rng(0)
    strokes = _letters(rng, 3)
    expected = perceive_trajectories(strokes, y_down=True)
    np.savez(tmp_path / "s.npz", traj=expected, text="abc")
    capture = {
        "schema": "prg.handwriting_capture",
        "version": 1,
        "samples": [
            {"word": c, "strokes": [[[float(x), float(y), 0.0, 0.5] for x, y in s]]}
            for c, s in zip("abc", strokes, strict=True)
        ]
        + [{"word": "cat", "strokes": [[[0, 0], [1, 1]]]}, {"word": "d", "strokes": []}],
    }
    (tmp_path / "s.json").write_text(json.dumps(capture))
    samples = [RawSample(c, "w1", "w1-01", [s], "uji") for c, s in zip("abc", strokes, strict=True)]
    (tmp_path / "s.txt").write_text(format_uji(samples))
    for name in ("s.npz", "s.json", "s.txt"):
        traj, labels = read_style(tmp_path / name)
        # a UJI file holds whole tablet units: its letters agree to that rounding
        np.testing.assert_allclose(traj, expected, atol=1e-5 if name != "s.txt" else 5e-3)
        assert [int(y) for y in labels] == [char_to_label(c) for c in "abc"]


@pytest.mark.parametrize(
    "name, content, match",
    [
        ("none.npz", None, "no such file"),
        ("bad.npz", b"not a zip", "not an .npz"),
        ("empty.json", b'{"schema": "prg.handwriting_capture", "samples": []}', "no single-stroke"),
        ("other.json", b'{"strokes": []}', "not a capture-page recording"),
    ],
)
def test_a_bad_style_file_is_one_clear_error(tmp_path, name, content, match):
    if content is not None:
        (tmp_path / name).write_bytes(content)
    with pytest.raises(UsageError, match=match):
        read_style(tmp_path / name)


def test_a_style_npz_with_the_wrong_shape_is_refused(tmp_path):
    np.savez(tmp_path / "s.npz", traj=np.zeros((2, 100)), text="ab")
    with pytest.raises(UsageError, match=r"accepted is \(k, 200\)"):
        read_style(tmp_path / "s.npz")


def test_a_persons_slant_is_found_and_put_on_the_letters_written_from_the_writers():
    """A person who writes writer 1's letters sheared: the match is writer 1, its map is the
    shear, and the letters written from writer 1's carry it."""
    from prg.pipeline.hands import STYLE_WRITERS, apply_transform, fit_transform, hand_distances

    bank = stand_in_hands(n_writers=3, seed=2)
    shear = np.array([[1.0, 0.25], [0.0, 1.0]])
    mine = np.flatnonzero(bank.writer == 1)[:6]
    own = apply_transform(bank.traj[mine].reshape(6, 100, 2), shear).reshape(6, -1)
    hand = match_hand(bank, own, bank.label[mine])
    assert hand.writer == 1 and hand.blend[0] == 1
    # writer 1's map is the shear up to the normalisation's scale, pulled a little to identity
    distances, maps = hand_distances(bank, own, bank.label[mine])
    direction = maps[1] / np.abs(maps[1]).max()
    np.testing.assert_allclose(direction, shear / np.abs(shear).max(), atol=0.05)
    np.testing.assert_allclose(fit_transform(own, own), np.eye(2), atol=1e-12)
    # the hand blends the nearest writers, nearest first, with the mean of their maps
    assert len(hand.blend) == min(STYLE_WRITERS, 3)
    assert list(hand.blend) == list(np.argsort(distances, kind="stable")[: len(hand.blend)])
    np.testing.assert_allclose(hand.transform, maps[list(hand.blend)].mean(0))
