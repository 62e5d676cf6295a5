"""Helpers shared by the tests that were split out of tests/test_word.py."""

from __future__ import annotations

import numpy as np
import pytest

from prg.data.preprocess import normalise, resample_arclength
from prg.pipeline.connect import connect_sequence
from prg.pipeline.dmp import fit_dmp
from prg.pipeline.layout import layout_letters, word_breaks
from prg.pipeline.word import (
    WordTrajectory,
    assemble_word,
)
from tests.conftest import letter_like

TEXT = "ab cd"


def letters_cm(text: str = TEXT, seed: int = 0) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    n = sum(c != " " for c in text)
    raw = [normalise(resample_arclength(letter_like(rng, 80), 100)) for _ in range(n)]
    return layout_letters(raw, text)


@pytest.fixture(scope="module")
def word() -> WordTrajectory:
    placed = letters_cm()
    connections = connect_sequence(placed, breaks=word_breaks(TEXT))
    dmp = fit_dmp(np.concatenate(placed), tau=1.5, n_basis=30)
    return assemble_word(placed, connections, TEXT, speed_cm_s=2.5, dmp=dmp)
