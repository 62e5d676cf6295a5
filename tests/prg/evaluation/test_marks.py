"""Tests of ``prg.evaluation.marks`` (moved from the suite on: delayed strokes (i/j dots, t/f
bars): placed on every letter that needs one, judged by the geometric check, and carried through
the word file, the figures, the motion, the recording, the simulated robot and the study
stimuli)."""

from __future__ import annotations

from prg.alphabet import ALPHABET
from prg.evaluation.marks import check_marks, check_writer, marks_figure, random_words
from prg.pipeline.compose import GenerateSettings
from prg.pipeline.marks import MarkSettings
from prg.pipeline.word import WordTrajectory
from tests.helpers.marks import _writer, dataset_letters  # noqa: F401 (fixtures)


def test_every_class_and_200_random_words_have_their_marks(dataset_letters, tmp_path):
    check = check_writer(_writer(dataset_letters), n_words=200, seed=1, progress=False)
    summary = check.summary()
    assert summary["failures"] == {}
    assert summary["classes_passed"] == 62 and summary["words_passed"] == 200
    # every dotted or crossed letter of the words got exactly one mark
    needed = sum(sum(c in "ijtf" for c in text) for text in [*ALPHABET, *random_words(200, 1)])
    assert summary["marks_checked"] == needed > 50
    figure = marks_figure(check, tmp_path / "marks.png")
    assert figure.stat().st_size > 10_000


def test_the_check_fails_when_a_mark_is_missing_or_misplaced(dataset_letters):
    word = _writer(dataset_letters)("tie")
    assert check_marks(word) == []
    marks = [k for k, kind in enumerate(word.segment_kinds) if kind == "mark"]
    bar, dot = (word.segment == marks[0]), (word.segment == marks[1])

    def moved(mask, shift):
        points = word.points.copy()
        points[mask] += shift
        return WordTrajectory(points, word.segment, word.segment_kinds, word.text)

    (_, t_points), (_, i_points) = word.letters[0], word.letters[1]
    below = moved(dot, [0.0, i_points[:, 1].min() - word.points[dot, 1].max() - 0.1])
    assert check_marks(below) == [
        "'i' (letter 2) has no dot above its stem",
        "1 mark(s) belong to no letter that needs one",
    ]
    aside = moved(dot, [i_points[:, 0].max() - word.points[dot, 0].min() + 0.3, 0.0])
    assert "'i' (letter 2) has no dot above its stem" in check_marks(aside)
    above = moved(bar, [0.0, t_points[:, 1].max() + 0.2 - word.points[bar, 1].min()])
    assert "'t' (letter 1) has no bar across its stem" in check_marks(above)
    single = _writer(dataset_letters, GenerateSettings(delayed_strokes=False))("tie")
    assert check_marks(single) == [
        "'t' (letter 1) has no bar across its stem",
        "'i' (letter 2) has no dot above its stem",
    ]
    # a mark on a letter that needs none is reported too
    extra = check_marks(word, MarkSettings(dotted="j", crossed="f"))
    assert extra == ["2 mark(s) belong to no letter that needs one"]
