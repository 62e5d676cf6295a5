"""The likeness table of generation modes and the style rates, on small known cases."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from torch import nn

from prg.alphabet import NUM_CLASSES
from prg.evaluation.modes import MODES, mode_rows, subsample
from prg.evaluation.styles import class_centred, style_rates, style_summary, writer_features
from tests.conftest import stand_in_hands


def _arrays(bank, writers):
    keep = np.isin(bank.writer, writers)
    return {
        "traj": bank.traj[keep],
        "label": bank.label[keep],
        "writer": np.array([bank.writers[w] for w in bank.writer[keep]]),
        "augmented": np.zeros(int(keep.sum()), dtype=bool),
    }


class NearestLetter(nn.Module):
    """A 1-nearest-neighbour letter classifier over known letters (logits: minus distances)."""

    def __init__(self, traj, labels):
        super().__init__()
        self.traj, self.labels = torch.as_tensor(traj), torch.as_tensor(labels)

    def forward(self, x):
        d = torch.cdist(x.reshape(len(x), -1).float(), self.traj.float())
        logits = torch.full((len(x), NUM_CLASSES), -1e9)
        for c in range(NUM_CLASSES):
            mine = self.labels == c
            if mine.any():
                logits[:, c] = -d[:, mine].min(1).values
        return logits


@pytest.fixture(scope="module")
def setting(untrained_muse_checkpoint):
    from prg.models.checkpoint import load_model

    model, info = load_model(untrained_muse_checkpoint)
    people = stand_in_hands(n_writers=4, seed=5)
    test = _arrays(people, [0, 1, 2, 3])
    return model, info["hands"], test


def test_real_letters_scored_against_themselves_are_a_perfect_row(setting):
    test = setting[2]
    classifier = NearestLetter(test["traj"], test["label"])
    rows = mode_rows({}, test, {"itself": test}, classifier, n_per_class=4)
    (row,) = rows
    assert (row["family"], row["mode"]) == ("real", "itself")
    for measure in ("legible", "precision", "recall", "spread"):
        assert row[measure] == pytest.approx(1.0), measure


def test_every_mode_is_a_row_and_the_posterior_mean_has_no_spread(setting):
    model, bank, test = setting
    classifier = NearestLetter(test["traj"], test["label"])
    rows = mode_rows({"muse": (model, bank)}, test, {}, classifier, n_per_class=4)
    assert [r["mode"] for r in rows] == [m.name for m in MODES]  # MUSE imputes and takes labels
    mean = next(r for r in rows if r["mode"] == "mean (paper)")
    assert mean["spread"] == 0.0  # one letter per class, however many are asked
    hand = next(r for r in rows if r["mode"] == "hand (default)")
    assert hand["spread"] > 0


def test_a_subsample_keeps_at_most_n_of_each_class():
    bank = stand_in_hands(n_writers=5)
    picked = subsample(bank.traj, bank.label, 3, seed=0)
    assert set(picked) == set(range(NUM_CLASSES))
    assert all(len(v) == 3 for v in picked.values())


def test_writer_features_ignore_position_and_see_slant():
    bank = stand_in_hands(n_writers=1)
    letters = bank.traj[:5].reshape(5, 100, 2)
    moved = (letters + np.array([0.3, -0.2])).reshape(5, -1)
    np.testing.assert_allclose(writer_features(moved), writer_features(bank.traj[:5]), atol=1e-9)
    sheared = (letters @ np.array([[1.0, 0.5], [0.0, 1.0]]).T).reshape(5, -1)
    slant = -2  # the principal axis angle
    assert not np.allclose(
        writer_features(sheared)[:, slant], writer_features(bank.traj[:5])[:, slant]
    )


def test_class_centring_subtracts_each_class_mean():
    features = np.array([[1.0, 2.0], [3.0, 4.0], [10.0, 0.0]])
    labels = np.array([0, 0, 1])
    means = {0: np.array([2.0, 3.0]), 1: np.array([10.0, 0.0])}
    np.testing.assert_array_equal(
        class_centred(features, labels, means), [[-1.0, -1.0], [1.0, 1.0], [0.0, 0.0]]
    )


def test_style_rates_report_each_seed_and_k_against_the_writers_own_letters(setting):
    model, bank, test = setting
    rows = style_rates(model, bank, test, ks=(1, 3), seeds=(0, 1), n_eval=6)
    assert [(r["seed"], r["k"]) for r in rows] == [(0, 1), (0, 3), (1, 1), (1, 3)]
    for r in rows:
        assert r["chance"] == 1 / 4 and r["writers"] == 4
        assert 0 <= r["generated"] <= 1 and 0 <= r["real"] <= 1
        assert r["letters"] == 4 * 6  # every writer wrote each set-aside class once
    summary = style_summary([{"family": "muse", **r} for r in rows])
    assert [s["k"] for s in summary] == [1, 3]
    first = summary[0]
    assert first["generated"] == pytest.approx(
        np.mean([rows[0]["generated"], rows[2]["generated"]])
    )
    assert first["ratio"] == pytest.approx(first["generated"] / first["real"])
