"""Helpers shared by the tests that were split out of tests/test_sim_geometry.py."""

from __future__ import annotations

import numpy as np

from prg.pipeline.connect import subdivide
from prg.pipeline.word import assemble_word


def _two_words() -> tuple:
    a = np.column_stack([np.linspace(0, 1, 20), np.zeros(20)])
    b = np.column_stack([np.linspace(1.2, 2, 10), np.zeros(10)])
    c = np.column_stack([np.linspace(3, 4, 20), np.ones(20)])
    travel = subdivide(b[-1], c[0], 0.05)[1:-1]
    word = assemble_word([a, b, c], [np.empty((0, 2)), travel], "ab c")
    return word, (b[-1], c[0])
