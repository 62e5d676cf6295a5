"""Tests of ``studies.stimuli.trajectories`` (moved from the suite on: delayed strokes (i/j dots,
t/f bars): placed on every letter that needs one, judged by the geometric check, and carried
through the word file, the figures, the motion, the recording, the simulated robot and the study
stimuli)."""

from __future__ import annotations

import numpy as np

from prg.pipeline.word import WordTrajectory
from studies.stimuli import (
    word_strokes,
)
from tests.helpers.marks import _writer, dataset_letters  # noqa: F401 (fixtures)


def test_the_study_stimulus_shows_the_marks(dataset_letters):
    from studies.stimuli import word_strokes

    word = _writer(dataset_letters)("tilt")
    strokes = word_strokes(word)
    assert len(strokes) == 1 + 3  # the word, then the two bars and the dot
    marks = [word.segment_points(k) for k, kind in enumerate(word.segment_kinds) if kind == "mark"]
    for stroke, mark in zip(strokes[1:], marks):
        np.testing.assert_array_equal(stroke, mark)


def test_pen_up_travel_is_not_ink():
    pts = np.array([[0, 0], [1, 0], [2, 0], [3, 0], [4, 0], [5, 0]], dtype=float)
    traj = WordTrajectory(pts, [0, 0, 1, 1, 2, 2], ["letter", "space", "letter"], "a b")
    strokes = word_strokes(traj)
    assert [s.tolist() for s in strokes] == [[[0, 0], [1, 0]], [[4, 0], [5, 0]]]
