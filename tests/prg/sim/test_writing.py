"""Tests of ``prg.sim.writing`` (moved from the suite on: the simulated robot writes: accuracy,
ink, lifts between words, workspace, IK, both arms, outputs, and the Rerun recording read back
from disk)."""

from __future__ import annotations

import numpy as np

from prg.sim import (
    font_word,
    simulate_word,
)


def test_two_words_are_two_strokes_with_the_pen_lifted_in_between():
    result = simulate_word(font_word("l l"), "panda", render=False)  # conf/simulate.yaml's settings
    m = result.metrics
    assert m["commanded_strokes"] == m["ink_strokes"] == 2
    assert m["ink_to_command_max_mm"] < 0.5  # no ink on the travel between the words
    travel = result.commanded[:, 2] > 1.0
    assert not np.any(result.contact & travel)
    first, second = result.ink_strokes()
    assert second[:, 0].min() - first[:, 0].max() > 0.5  # the space between the words
