"""Tests of ``studies.stimuli.pilot`` (moved from the suite on: prg-study judge: a classifier two-
sample test and a simulated observer on a built study; and a pilot's human words from held-out
writers)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from prg.errors import UsageError
from studies.design import ROBOT
from studies.stimuli import (
    Sample,
    held_out_words,
    render_sample,
    stand_ins,
    trajectory_sample,
)
from tests.helpers.browser import wobbly_word
from tests.helpers.study_stimuli import STYLE, marked_word


def test_a_pilots_human_words_are_held_out_writers_letters_joined(small_dataset, tmp_path):
    data = small_dataset / "prepared" / "synthetic"
    made = held_out_words(["ab", "cd"], 2, data, tmp_path / "pilot", seed=0)
    for word, samples in made.items():
        assert len(samples) == 2 and {s.word for s in samples} == {word}
        assert len({s.writer_id for s in samples}) == 2
        for s in samples:
            assert Path(s.origin).is_file() and s.writer_id.startswith("pilot-")
    with pytest.raises(UsageError, match="held-out writers wrote every letter"):
        held_out_words(["ab"], 99, data, tmp_path / "pilot")


def test_pilot_stand_ins_are_distinct_deterministic_and_named_as_such():
    robot = Sample("cat", ROBOT, (wobbly_word("cat", np.random.default_rng(0)),))
    made = stand_ins(robot, 3, seed=1)
    assert [s.writer_id for s in made] == ["pilot01", "pilot02", "pilot03"]
    pictures = [np.asarray(render_sample(s, STYLE), dtype=int) for s in [robot, *made]]
    for i in range(4):
        for j in range(i):
            assert np.abs(pictures[i] - pictures[j]).mean() > 1
    again = stand_ins(robot, 3, seed=1)
    for a, b in zip(made, again):
        np.testing.assert_array_equal(a.strokes[0], b.strokes[0])


def test_pilot_stand_ins_keep_the_robots_dots_and_bars_as_delayed_strokes():
    robot = trajectory_sample(marked_word("fit"), ROBOT, "composed")
    assert robot.delayed == (1, 2, 3)  # f's bar, i's dot, t's bar
    for made in stand_ins(robot, 3, seed=4):
        assert made.delayed == robot.delayed and not made.lifted
        body = made.strokes[0]
        for k in made.delayed:
            before, after = robot.strokes[k], made.strokes[k]
            assert np.ptp(after, axis=0).max() <= 1.5 * np.ptp(before, axis=0).max() + 1e-9
            # it moves with the word: still next to the nearest point of the wobbled body
            gap = np.hypot(*(body - after.mean(axis=0)).T).min()
            original = np.hypot(*(robot.strokes[0] - before.mean(axis=0)).T).min()
            assert gap < original + 0.3 * np.ptp(robot.strokes[0][:, 1])
    for made in stand_ins(robot, 2, seed=4, delayed_strokes=False):
        assert len(made.strokes) == 1 and made.delayed == ()


def test_a_pilot_writers_letters_are_drawn_anew_among_their_samples_of_the_class():
    """Every letter is one of the writer's own samples of its class; a class written several
    times is not one copied sample each time (over seeds both of its samples appear)."""
    from studies.stimuli.pilot import letter_samples

    labels = np.array([0, 0, 1, 1, 0, 1, 2])
    writers = np.array(["w1", "w1", "w1", "w1", "w2", "w2", "w1"])
    wanted = [0, 0, 1, 2, 0]
    seen = set()
    for seed in range(20):
        rows = letter_samples(labels, writers, "w1", wanted, np.random.default_rng(seed))
        assert rows.dtype == np.int64 and len(rows) == len(wanted)
        assert (writers[rows] == "w1").all() and (labels[rows] == wanted).all()
        assert rows[3] == 6  # the writer's only sample of class 2
        seen.update((i, int(r)) for i, r in enumerate(rows))
    for i, y in enumerate(wanted[:3]):
        assert {r for j, r in seen if j == i} == set(
            np.flatnonzero((writers == "w1") & (labels == y))
        )
