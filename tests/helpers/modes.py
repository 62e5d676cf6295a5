"""Helpers shared by the tests that were split out of tests/test_modes.py."""

from __future__ import annotations

import numpy as np
import pytest

from tests.conftest import stand_in_hands


def _arrays(bank, writers):
    keep = np.isin(bank.writer, writers)
    return {
        "traj": bank.traj[keep],
        "label": bank.label[keep],
        "writer": np.array([bank.writers[w] for w in bank.writer[keep]]),
        "augmented": np.zeros(int(keep.sum()), dtype=bool),
    }


@pytest.fixture(scope="module")
def setting(untrained_muse_checkpoint):
    from prg.models.checkpoint import load_model

    model, info = load_model(untrained_muse_checkpoint)
    people = stand_in_hands(n_writers=4, seed=5)
    test = _arrays(people, [0, 1, 2, 3])
    return model, info["hands"], test
