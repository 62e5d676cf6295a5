"""Helpers shared by the tests that were split out of tests/test_marks.py."""

from __future__ import annotations

import numpy as np
import pytest

from prg.alphabet import ALPHABET, char_to_label
from prg.pipeline.compose import compose_word
from prg.pipeline.word import WordTrajectory


@pytest.fixture(scope="module")
def dataset_letters(small_dataset):
    """Letters of the prepared synthetic dataset by class: the handwriting the models learn."""
    split = np.load(small_dataset / "prepared" / "synthetic" / "train.npz")
    traj, label = split["traj"], split["label"]
    return {c: traj[label == char_to_label(c)].reshape(-1, 100, 2) for c in ALPHABET}


def _writer(letters_by_class, params=None, seed=0):
    rng = np.random.default_rng(seed)

    def write(text: str) -> WordTrajectory:
        chars = text.replace(" ", "")
        letters = [letters_by_class[c][rng.integers(len(letters_by_class[c]))] for c in chars]
        return compose_word(np.stack(letters), text, params)[0]

    return write


def _t_with_return():
    """A one-stroke t: down the stem, round the foot, back up the right and across to the left."""
    stem = np.column_stack([np.zeros(20), np.linspace(1.5, 0.1, 20)])
    angle = np.linspace(np.pi, 2 * np.pi, 12)[1:]
    foot = np.column_stack([0.2 + 0.2 * np.cos(angle), 0.2 + 0.2 * np.sin(angle)])
    up = np.column_stack([np.full(10, 0.4), np.linspace(0.3, 1.0, 10)])
    across = np.column_stack([np.linspace(0.3, -0.3, 10), np.full(10, 1.0)])
    return np.vstack([stem, foot, up, across])
