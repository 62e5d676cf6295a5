"""Tests of ``prg.plotting`` (moved from the suite on: rerun recordings: a written word with its
inputs and animated DMP rollout, read back from disk)."""

from __future__ import annotations

import numpy as np

from prg.recording import (
    distinct_colours,
)


def test_connection_colours_are_distinct_for_long_words():
    colours = distinct_colours(40)
    assert colours.shape == (40, 3) and colours.dtype == np.uint8
    assert len({tuple(c) for c in colours}) == 40
