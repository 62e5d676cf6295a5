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

        def generation_posterior(self, inputs, impute_steps):
            return inputs["label"]

        def decode_posterior(self, label, inputs, target, n, temperature):
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


def _muse(checkpoint):
    from prg.models.checkpoint import load_model

    return load_model(checkpoint)[0]


def test_shared_posteriors_decode_what_generate_decodes_and_impute_once(untrained_muse_checkpoint):
    """Sharing one imputed posterior between the targets and the kinds changes no generated
    sample, and imputes each (subset, batch) once however many cells decode from it."""
    from prg.evaluation.coherence import Posteriors, generated_samples

    model = _muse(untrained_muse_checkpoint)
    g = torch.Generator().manual_seed(0)
    data = {
        "traj": torch.randn(10, 200, generator=g),
        "label": torch.randint(0, 62, (10,), generator=g),
        "image": torch.rand(10, 1, 28, 28, generator=g),
    }
    calls = []
    impute = model.encode_imputed
    model.encode_imputed = lambda inputs, steps: calls.append(steps) or impute(inputs, steps)
    shared = Posteriors(model, data)
    for target in ("traj", "image", "label"):
        for temperature in (0.0, 1.0):
            alone = generated_samples(model, target, ("label",), data, temperature, 4, 3, 5)
            together = generated_samples(
                model, target, ("label",), data, temperature, 4, 3, 5, shared
            )
            assert torch.equal(alone, together), (target, temperature)
    # 6 cells computed alone impute each of the 3 batches; shared, the 3 batches once
    assert len(calls) == 6 * 3 + 3
    with pytest.raises(ValueError, match="another model or another test set"):
        generated_samples(model, "traj", ("label",), dict(data), 0.0, 4, 3, 5, shared)
