"""Tests of ``prg.pipeline.marks`` (moved from the suite on: delayed strokes (i/j dots, t/f bars):
placed on every letter that needs one, judged by the geometric check, and carried through the
word file, the figures, the motion, the recording, the simulated robot and the study stimuli)."""

from __future__ import annotations

import numpy as np
import pytest

from prg.errors import SettingsError, UsageError
from prg.pipeline.compose import GenerateSettings
from prg.pipeline.marks import MarkSettings
from prg.pipeline.word import WordTrajectory, assemble_word
from tests.helpers.marks import _t_with_return, _writer, dataset_letters  # noqa: F401 (fixtures)


def test_marks_sit_where_the_rules_say(dataset_letters):
    word = _writer(dataset_letters)("itjf")
    marks = [word.segment_points(k) for k, kind in enumerate(word.segment_kinds) if kind == "mark"]
    assert len(marks) == 4
    settings, layout = MarkSettings(), GenerateSettings().layout
    for (char, letter), mark in zip(word.letters, marks):
        top = letter[np.argmax(letter[:, 1])]
        height = np.ptp(letter[:, 1])
        if char in "ij":  # a closed circle above the stem's top, at the stem's x
            centre = (mark.min(axis=0) + mark.max(axis=0)) / 2
            np.testing.assert_allclose(mark[0], mark[-1], atol=1e-12)
            assert centre[0] == pytest.approx(top[0], abs=1e-9)
            scale = np.clip(height / (layout.x_height * layout.letter_height), 0.25, 1.0)
            gap = mark[:, 1].min() - top[1]
            assert gap == pytest.approx(settings.dot_gap * layout.letter_height * scale, rel=1e-6)
        else:  # a horizontal bar, left to right, crossing the letter's path
            assert np.all(np.diff(mark[:, 0]) > 0) and np.ptp(mark[:, 1]) == 0
            y = mark[0, 1]
            assert letter[:, 1].min() < y < letter[:, 1].max()


def test_segments_out_of_order_and_bad_settings_are_refused(dataset_letters):
    word = _writer(dataset_letters)("i")
    kinds = list(word.segment_kinds)
    with pytest.raises(UsageError, match="delayed strokes must come after the body"):
        WordTrajectory(word.points, word.segment, [*kinds[:-2], "mark", "lift"], word.text)
    with pytest.raises(UsageError, match="shape"):
        assemble_word([word.letters[0][1]], [], "i", marks=[np.zeros((1, 2))])
    with pytest.raises(SettingsError, match="dot_radius"):
        MarkSettings(dot_radius=0)
    with pytest.raises(SettingsError, match="'t' is also dotted"):
        MarkSettings(dotted="it", crossed="t")
    with pytest.raises(SettingsError, match="dotted"):
        MarkSettings(dotted="i!")
    with pytest.raises(SettingsError, match="delayed_strokes"):
        GenerateSettings(delayed_strokes="yes")


def test_a_crossed_letter_ends_at_its_foot_when_its_path_returns_for_the_bar():
    from prg.pipeline.marks import EXIT_RISE, crossed_exit

    t = _t_with_return()
    cut = crossed_exit(t)
    assert len(cut) < len(t) and np.array_equal(cut, t[: len(cut)])  # a prefix
    height = np.ptp(t[:, 1])
    rise = cut[-1, 1] - t[:, 1].min()
    assert EXIT_RISE * height < rise <= EXIT_RISE * height + 0.1  # just past the rise
    assert cut[-1, 0] > 0.3  # left on the right of the stem, not back across it


def test_a_crossed_letter_that_leaves_to_the_right_or_ends_at_its_foot_is_kept_whole():
    from prg.pipeline.marks import crossed_exit

    t = _t_with_return()
    leaves_right = np.vstack(
        [t[:35], np.column_stack([np.linspace(0.4, 1.2, 10), np.linspace(0.4, 0.8, 10)])]
    )
    assert np.array_equal(crossed_exit(leaves_right), leaves_right)
    ends_at_foot = t[:25]
    assert np.array_equal(crossed_exit(ends_at_foot), ends_at_foot)
