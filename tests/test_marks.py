"""Delayed strokes (i/j dots, t/f bars): placed on every letter that needs one, judged by the
geometric check, and carried through the word file, the figures, the motion, the recording, the
simulated robot and the study stimuli."""

from __future__ import annotations

import json

import numpy as np
import pytest

from prg.alphabet import ALPHABET, char_to_label
from prg.errors import SettingsError, UsageError
from prg.evaluation.marks import check_marks, check_writer, marks_figure, random_words
from prg.pipeline.compose import GenerateSettings, compose_word
from prg.pipeline.marks import MarkSettings
from prg.pipeline.word import WordTrajectory, assemble_word
from prg.sim import word_samples
from prg.sim.geometry import runs


@pytest.fixture(scope="module")
def dataset_letters(small_dataset):
    """Letters of the prepared synthetic dataset by class: the handwriting the models learn."""
    split = np.load(small_dataset / "prepared" / "synthetic" / "train.npz")
    traj, label = split["traj"], split["label"]
    return {c: traj[label == char_to_label(c)].reshape(-1, 100, 2) for c in ALPHABET}


def _writer(letters_by_class, params=None, seed=0):
    rng = np.random.default_rng(seed)

    def write(text: str) -> WordTrajectory:
        chars = text.replace(" ", "")
        letters = [letters_by_class[c][rng.integers(len(letters_by_class[c]))] for c in chars]
        return compose_word(np.stack(letters), text, params)[0]

    return write


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


def test_delayed_strokes_false_is_the_papers_single_stroke(dataset_letters):
    write = _writer(dataset_letters, GenerateSettings(delayed_strokes=False))
    word = write("quiz")
    assert "mark" not in word.segment_kinds and word.body_end == len(word.points)
    assert len(runs(word.pen_down())) == 1


def test_the_motion_writes_the_body_then_lifts_to_each_mark(dataset_letters):
    word = _writer(dataset_letters)("quiz jut")
    samples, t, down = word_samples(word, dt=1 / 60)
    assert np.all(np.diff(t) > 0) and t[-1] == pytest.approx(word.duration_s, rel=1e-9)
    # strokes: "quiz", "jut", then the dots of i and j and the bar of t, in that order
    strokes = [samples[a:b] for a, b in runs(down)]
    assert len(strokes) == 5
    marks = [word.segment_points(k) for k, kind in enumerate(word.segment_kinds) if kind == "mark"]
    for stroke, mark in zip(strokes[2:], marks):
        np.testing.assert_allclose(stroke[0], mark[0], atol=1e-9)  # the pen lowers on it
        np.testing.assert_allclose(stroke[-1], mark[-1], atol=1e-9)
    np.testing.assert_allclose(samples[0], word.points[0], atol=1e-9)  # the DMP's start
    tempo_2 = word_samples(word, dt=1 / 60, tempo=2.0)[1]
    assert tempo_2[-1] == pytest.approx(2 * word.duration_s, rel=1e-9)


def test_the_word_file_keeps_the_marks_and_reads_version_1(dataset_letters, tmp_path):
    word = _writer(dataset_letters)("kit")
    path = word.to_json(tmp_path / "word.json")
    back = WordTrajectory.from_json(path)
    assert back.segment_kinds == word.segment_kinds and back.body_end == word.body_end
    np.testing.assert_array_equal(back.points, word.points)
    old = _writer(dataset_letters, GenerateSettings(delayed_strokes=False))("kit").to_dict()
    old["version"] = 1
    (tmp_path / "v1.json").write_text(json.dumps(old))
    assert WordTrajectory.from_json(tmp_path / "v1.json").segment_kinds.count("mark") == 0


def test_figures_draw_marks_as_ink_and_no_lift(dataset_letters, tmp_path):
    word = _writer(dataset_letters)("it")
    ink = word.to_svg(tmp_path / "ink.svg", highlight=False).read_text()
    assert ink.count('class="mark"') == 2 and 'class="lift"' not in ink
    shown = word.to_svg(tmp_path / "shown.svg").read_text()
    assert shown.count('class="lift"') == 2
    pieces = word.polylines(highlight=False)
    for (_, pts), mark in zip(
        [p for p in pieces if p[0] == "mark"],
        [word.segment_points(k) for k, kind in enumerate(word.segment_kinds) if kind == "mark"],
    ):
        np.testing.assert_array_equal(pts, mark)  # a stroke of its own, not joined to the word


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


def test_the_recording_draws_the_marks_and_no_ink_over_a_lift(dataset_letters, tmp_path):
    from prg.recording import read_component, read_entities, read_times, record_write

    letters = [dataset_letters[c][0] for c in "it"]
    word, rollout = compose_word(np.stack(letters), "it")
    path = record_write(tmp_path / "word.rrd", word, rollout)
    entities = read_entities(path)
    assert {"word/marks/0", "word/marks/1", "word/pen_up/0", "word/pen_up/1"} <= set(entities)
    times = read_times(path, "word/rollout/pen", "time")
    assert times[-1] == pytest.approx(word.duration_s, abs=1e-6)
    assert times[len(rollout) - 1] == pytest.approx(word.dmp.tau, abs=1e-6)
    # every inked segment lies on the body or on a mark, none on the travel between them
    segments = np.concatenate(
        [
            np.array(row[0])
            for row in read_component(path, "word/rollout/path", "LineStrips2D:strips", "time")
        ]
    )
    marks = [word.segment_points(k) for k, kind in enumerate(word.segment_kinds) if kind == "mark"]
    ink = np.concatenate([word.body, *marks]) * [1.0, -1.0]  # recorded y-flipped
    nearest = np.min(np.linalg.norm(segments[:, None, :] - ink[None], axis=2), axis=1)
    assert nearest.max() < 0.05  # cm: the DMP's rollout and the timed marks follow the ink
    lifts = np.concatenate(
        [word.segment_points(k) for k, kind in enumerate(word.segment_kinds) if kind == "lift"]
    )
    assert len(lifts) > 3 and len(segments) > 100


def test_the_study_stimulus_shows_the_marks(dataset_letters):
    from studies.stimuli import word_strokes

    word = _writer(dataset_letters)("tilt")
    strokes = word_strokes(word)
    assert len(strokes) == 1 + 3  # the word, then the two bars and the dot
    marks = [word.segment_points(k) for k, kind in enumerate(word.segment_kinds) if kind == "mark"]
    for stroke, mark in zip(strokes[1:], marks):
        np.testing.assert_array_equal(stroke, mark)


def test_a_words_dmp_starts_and_ends_at_rest(dataset_letters):
    """The word pipeline keeps the rest-to-rest DMP (prg.pipeline.dmp: ``velocities="rest"``):
    the pen is still at the first and last samples of the rollout."""
    letters = [dataset_letters[c][0] for c in "joy"]
    word, rollout = compose_word(np.stack(letters), "joy")
    assert not word.dmp.start_velocity.any() and not word.dmp.goal_velocity.any()
    step = word.dmp.tau / (len(rollout) - 1)
    speeds = np.linalg.norm(np.diff(rollout, axis=0), axis=1) / step
    assert speeds[0] < 0.01 * np.median(speeds) and speeds[-1] < 0.01 * np.median(speeds)


def _t_with_return():
    """A one-stroke t: down the stem, round the foot, back up the right and across to the left."""
    stem = np.column_stack([np.zeros(20), np.linspace(1.5, 0.1, 20)])
    angle = np.linspace(np.pi, 2 * np.pi, 12)[1:]
    foot = np.column_stack([0.2 + 0.2 * np.cos(angle), 0.2 + 0.2 * np.sin(angle)])
    up = np.column_stack([np.full(10, 0.4), np.linspace(0.3, 1.0, 10)])
    across = np.column_stack([np.linspace(0.3, -0.3, 10), np.full(10, 1.0)])
    return np.vstack([stem, foot, up, across])


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


def test_words_with_a_returning_t_leave_it_from_its_foot_only_with_delayed_strokes():
    t = _t_with_return()
    dot = np.column_stack([np.linspace(0, 0.5, len(t)), np.linspace(0, 0.5, len(t))])
    letters = np.stack([t, dot])
    with_bar = compose_word(letters, "ta", GenerateSettings(method="straight"))[0]
    without = compose_word(
        letters, "ta", GenerateSettings(method="straight", delayed_strokes=False)
    )[0]
    first = lambda word: word.points[word.segment == 0]  # noqa: E731
    assert len(first(with_bar)) < len(first(without)) == len(t)
