"""Helpers shared by the tests that were split out of tests/test_study_stimuli.py."""

from __future__ import annotations

import numpy as np

from prg.pipeline.compose import compose_word
from prg.pipeline.word import WordTrajectory
from studies.stimuli import (
    RenderStyle,
)

STYLE = RenderStyle(width_px=400, height_px=100, margin_px=10, stroke_px=4.0)


def marked_word(text: str) -> WordTrajectory:
    """A word composed as ``prg-write`` composes it (layout, connections, delayed strokes),
    from letters that are each one up-and-down stroke (no model needed)."""
    u = np.linspace(0, 1, 100)
    letter = np.column_stack([0.3 * np.sin(np.pi * u), 1 - 2 * np.abs(2 * u - 1)])
    word, _ = compose_word(np.stack([letter] * len(text)), text)
    return word
