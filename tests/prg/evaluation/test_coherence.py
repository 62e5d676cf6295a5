"""Tests of ``prg.evaluation.coherence`` (moved from the suite on: `prg-evaluate`: Table I,
coherence and robustness reports from real (tiny) trained models, written atomically, logged to
a real SQLite MLflow store; bad input gets one line)."""

import numpy as np
import pytest
import torch

from prg.alphabet import ALPHABET
from prg.evaluation.coherence import folded_correct, per_class_rate


def test_per_class_rate_matches_a_direct_count():
    rng = np.random.default_rng(0)
    labels = rng.integers(0, 5, 200)
    correct = rng.random(200) < 0.3
    rates = per_class_rate(torch.from_numpy(correct), torch.from_numpy(labels), 7).numpy()
    for c in range(5):
        assert rates[c] == pytest.approx(correct[labels == c].mean())
    assert np.isnan(rates[5:]).all()


def test_folded_counts_a_shape_twin_as_right_and_nothing_else():
    pairs = [("o", "O", True), ("o", "0", True), ("l", "I", True), ("x", "X", True)]
    pairs += [("o", "a", False), ("1", "l", False), ("h", "k", False), ("b", "b", True)]
    predicted = torch.tensor([ALPHABET.index(p) for _, p, _ in pairs])
    labels = torch.tensor([ALPHABET.index(t) for t, _, _ in pairs])
    assert folded_correct(predicted, labels).tolist() == [ok for *_, ok in pairs]


def test_readings_share_the_generated_samples_and_labels_have_one():
    from prg.evaluation.coherence import generated_readings

    class Echo:
        """A stand-in model: the generated trajectory's first value is the input label."""

        def generate(self, inputs, target, n, temperature, impute_steps):
            label = inputs["label"]
            if target == "label":
                return torch.nn.functional.one_hot(label, 62).float()[None]
            out = torch.zeros(len(label), 200)
            out[:, 0] = label.float()
            return out[None]

    data = {"label": torch.arange(7)}
    readers = [lambda x: x[:, 0].long(), lambda x: x[:, 0].long() + 1]
    readings = generated_readings(Echo(), "traj", ("label",), data, readers, batch_size=3)
    assert readings.shape == (7, 2)
    assert readings[:, 0].tolist() == list(range(7))
    assert (readings[:, 1] - readings[:, 0]).tolist() == [1] * 7
    labels = generated_readings(Echo(), "label", ("label",), data, readers, batch_size=3)
    assert labels.shape == (7, 1) and labels[:, 0].tolist() == list(range(7))
