"""Tests of ``prg.pipeline.motion`` (moved from the suite on: delayed strokes (i/j dots, t/f bars):
placed on every letter that needs one, judged by the geometric check, and carried through the
word file, the figures, the motion, the recording, the simulated robot and the study stimuli)."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from prg.sim import word_samples
from prg.sim.geometry import (
    arc_progress,
    runs,
)
from tests.helpers.marks import _writer, dataset_letters  # noqa: F401 (fixtures)


def test_the_motion_writes_the_body_then_lifts_to_each_mark(dataset_letters):
    word = _writer(dataset_letters)("quiz jut")
    samples, t, down = word_samples(word, dt=1 / 60)
    assert np.all(np.diff(t) > 0) and t[-1] == pytest.approx(word.duration_s, rel=1e-9)
    # strokes: "quiz", "jut" (one more for each place the pen lifts within a word, after a
    # print descender: prg.pipeline.joins.lifts_pen), then the dots of i and j and the bar of t,
    # in that order
    strokes = [samples[a:b] for a, b in runs(down)]
    body = word.segment_kinds.count("space") + 1
    assert body >= 2 and len(strokes) == body + 3
    marks = [word.segment_points(k) for k, kind in enumerate(word.segment_kinds) if kind == "mark"]
    for stroke, mark in zip(strokes[body:], marks):
        np.testing.assert_allclose(stroke[0], mark[0], atol=1e-9)  # the pen lowers on it
        np.testing.assert_allclose(stroke[-1], mark[-1], atol=1e-9)
    np.testing.assert_allclose(samples[0], word.points[0], atol=1e-9)  # the DMP's start
    tempo_2 = word_samples(word, dt=1 / 60, tempo=2.0)[1]
    assert tempo_2[-1] == pytest.approx(2 * word.duration_s, rel=1e-9)


def test_the_simulator_re_exports_the_pipelines_motion_functions():
    import prg.sim
    import prg.sim.geometry
    import prg.sim.writing
    from prg.pipeline import motion

    assert prg.sim.word_samples is prg.sim.writing.word_samples is motion.word_samples
    for name in ("arc_length", "arc_progress", "pen_down_samples"):
        assert getattr(prg.sim.geometry, name) is getattr(motion, name)
    assert prg.sim.pen_down_samples is motion.pen_down_samples


def test_arc_progress_follows_a_self_crossing_path_in_order():
    # a loop that crosses its own start segment: nearest-point projection alone would jump
    t = np.linspace(0, 1, 400)
    path = np.column_stack([np.sin(2 * np.pi * t) * (1 + t), np.sin(4 * np.pi * t)])
    samples = path[::3] + 1e-4
    s = arc_progress(path, samples)
    arc = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
    assert np.all(np.diff(s) >= 0)
    assert_allclose(s, arc[::3], atol=2e-3)


def test_a_word_without_a_dmp_is_followed_at_its_speed():
    from dataclasses import replace

    from prg.sim import font_word, word_samples

    word = replace(font_word("ab"), dmp=None, duration_s=None)
    samples, t, _ = word_samples(word, dt=1 / 100)
    assert t[-1] == pytest.approx(word.path_length / word.speed_cm_s)
    assert_allclose(samples[[0, -1]], word.points[[0, -1]], atol=1e-9)
