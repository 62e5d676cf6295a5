"""Tests of ``studies.stimuli.svg`` (moved from the suite on: stimuli: reading robot and human
samples, and drawing every one of them alike)."""

from __future__ import annotations

import numpy as np
import pytest

from prg.errors import UsageError
from studies.stimuli import (
    path_strokes,
)


def test_svg_curves_are_sampled_and_pass_through_their_end_points():
    (stroke,) = path_strokes("M0 0 C 0 10 10 10 10 0 S 20 -10 20 0 Q 25 5 30 0 T 40 0", "x")
    for end in ([10, 0], [20, 0], [30, 0], [40, 0]):
        assert np.min(np.hypot(*(stroke - end).T)) < 1e-9
    assert stroke[:, 1].max() == pytest.approx(7.5)  # the cubic's peak
    with pytest.raises(UsageError, match="malformed SVG path data"):
        path_strokes("M 0 0 L 5", "x")
