"""Tests of ``prg.evaluation.modes`` (moved from the suite on: the likeness table of generation
modes and the style rates, on small known cases)."""

from __future__ import annotations

import pytest
import torch
from torch import nn

from prg.alphabet import NUM_CLASSES
from prg.evaluation.modes import MODES, mode_rows, subsample
from tests.conftest import stand_in_hands
from tests.helpers.modes import setting  # noqa: F401 (fixtures)


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


def test_real_letters_scored_against_themselves_are_a_perfect_row(setting):
    test = setting[2]
    classifier = NearestLetter(test["traj"], test["label"])
    rows = mode_rows({}, test, {"itself": test}, classifier, n_per_class=4)
    (row,) = rows
    assert (row["family"], row["mode"]) == ("real", "itself")
    for measure in ("legible", "precision", "recall", "spread"):
        assert row[measure] == pytest.approx(1.0), measure


def test_legible_shape_is_the_second_readers_folded_rate_and_absent_without_one(setting):
    test = setting[2]
    classifier = NearestLetter(test["traj"], test["label"])
    alone = mode_rows({}, test, {"itself": test}, classifier, n_per_class=4)[0]
    assert alone["legible_shape"] != alone["legible_shape"]  # NaN: no second reader given

    def one_class(letters):  # reads every letter as class 10 ('A'; no shape twin)
        return torch.full((len(letters),), 10)

    row = mode_rows({}, test, {"itself": test}, classifier, 4, shape_reader=one_class)[0]
    labels = test["label"][~test["augmented"]] if "augmented" in test else test["label"]
    classes = sorted(set(labels.tolist()))
    # 4 letters of each class present (or all of a class with fewer), only class 10 read right
    sizes = {c: min(4, int((labels == c).sum())) for c in classes}
    assert row["legible_shape"] == pytest.approx(sizes.get(10, 0) / sum(sizes.values()))
    assert row["legible"] == pytest.approx(1.0)  # the first reader is unchanged


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
