"""The simulator's numeric core (no PyBullet): paper frame, pen-down samples, ink, errors, plan."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from numpy.testing import assert_allclose

from prg.errors import SettingsError, UsageError
from prg.pipeline.connect import subdivide
from prg.pipeline.timing import min_jerk
from prg.pipeline.word import assemble_word
from prg.sim.geometry import (
    Paper,
    arc_progress,
    distance_to_polylines,
    in_contact,
    max_ink_gap,
    pen_down_samples,
    place_points,
    runs,
    tracking_error,
)
from prg.sim.plan import PHASES, MotionSettings, plan_motion


def _circle(n: int = 200, radius: float = 1.0, centre=(0.0, 0.0)) -> np.ndarray:
    a = np.linspace(0, 2 * np.pi, n)
    return np.column_stack([np.cos(a), np.sin(a)]) * radius + np.asarray(centre)


def test_paper_frame_puts_the_writing_line_along_world_minus_y_and_round_trips():
    paper = Paper(size_cm=(42.0, 29.7), centre=(0.55, 0.0, 0.6255), yaw_deg=-90.0)
    world = paper.to_world([[10.0, 0.0, 0.0], [0.0, 10.0, 0.0], [0.0, 0.0, 2.0]])
    assert_allclose(world[0], [0.55, -0.10, 0.6255], atol=1e-12)  # x: the robot's right
    assert_allclose(world[1], [0.65, 0.0, 0.6255], atol=1e-12)  # y: up the page, away
    assert_allclose(world[2], [0.55, 0.0, 0.6455], atol=1e-12)  # height above the paper
    rng = np.random.default_rng(0)
    pts = rng.uniform(-10, 10, (50, 3))
    assert_allclose(paper.to_paper(paper.to_world(pts)), pts, atol=1e-9)
    assert paper.contains(np.array([[20.9, 14.8], [21.1, 0.0]])).tolist() == [True, False]


def test_paper_rejects_a_bad_size_naming_it():
    with pytest.raises(SettingsError, match=r"^size_cm must be two positive numbers") as err:
        Paper(size_cm=(0.0, 10.0))
    assert err.value.field == "size_cm"
    from prg.sim import SimSettings

    with pytest.raises(UsageError, match=r"^paper\.size_cm must be two positive numbers"):
        SimSettings.from_mapping({"paper": {"size_cm": [0.0, 10.0]}})


def test_place_points_scales_about_the_anchor_and_moves_it_to_the_target():
    out = place_points([[1.0, 1.0], [3.0, 1.0]], anchor=[2.0, 1.0], scale=2.0, target=[0.0, 5.0])
    assert_allclose(out, [[-2.0, 5.0], [2.0, 5.0]])


def test_arc_progress_follows_a_self_crossing_path_in_order():
    # a loop that crosses its own start segment: nearest-point projection alone would jump
    t = np.linspace(0, 1, 400)
    path = np.column_stack([np.sin(2 * np.pi * t) * (1 + t), np.sin(4 * np.pi * t)])
    samples = path[::3] + 1e-4
    s = arc_progress(path, samples)
    arc = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
    assert np.all(np.diff(s) >= 0)
    assert_allclose(s, arc[::3], atol=2e-3)


def _two_words() -> tuple:
    a = np.column_stack([np.linspace(0, 1, 20), np.zeros(20)])
    b = np.column_stack([np.linspace(1.2, 2, 10), np.zeros(10)])
    c = np.column_stack([np.linspace(3, 4, 20), np.ones(20)])
    travel = subdivide(b[-1], c[0], 0.05)[1:-1]
    word = assemble_word([a, b, c], [np.empty((0, 2)), travel], "ab c")
    return word, (b[-1], c[0])


def test_pen_down_samples_are_false_only_on_the_travel_between_words():
    word, (end, start) = _two_words()
    from prg.pipeline.timing import rest_to_rest_samples

    samples, _ = rest_to_rest_samples(word.points, 2.0, 0.3, 200)
    down = pen_down_samples(word.points, word.segment, word.segment_kinds, samples)
    assert len(runs(down)) == 2
    up = samples[~down]
    # strictly between the two words, on the straight travel
    assert np.all(up[:, 0] > end[0]) and np.all(up[:, 0] < start[0])
    assert down[0] and down[-1]


def test_in_contact_is_the_band_either_side_of_the_surface():
    heights_cm = np.array([-0.06, -0.05, 0.0, 0.049, 0.051, 1.5])
    assert in_contact(heights_cm, band_mm=0.5).tolist() == [False, True, True, True, False, False]
    with pytest.raises(UsageError, match="contact band"):
        in_contact(heights_cm, 0.0)


def test_distance_to_polylines_matches_brute_force_and_never_joins_strokes():
    rng = np.random.default_rng(1)
    lines = [np.cumsum(rng.normal(0, 0.3, (k, 2)), axis=0) for k in (30, 1, 12)]
    pts = rng.uniform(-3, 3, (300, 2))

    def brute(p):
        best = np.inf
        for line in lines:
            if len(line) == 1:
                best = min(best, np.linalg.norm(p - line[0]))
            for a, b in itertools.pairwise(line):
                u = np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0, 1)
                best = min(best, np.linalg.norm(a + u * (b - a) - p))
        return best

    assert_allclose(distance_to_polylines(pts, lines), [brute(p) for p in pts], atol=1e-12)
    # the gap between two strokes is not a segment
    two = [np.array([[0.0, 0.0], [1.0, 0.0]]), np.array([[3.0, 0.0], [4.0, 0.0]])]
    assert distance_to_polylines([[2.0, 0.0]], two)[0] == pytest.approx(1.0)


def test_tracking_error_of_ink_offset_by_a_tenth_of_a_millimetre():
    command = [_circle(400)]
    ink = [_circle(1600, radius=1.01)]  # 0.01 cm = 0.1 mm outside
    err = tracking_error(command, ink)
    assert err["mean_mm"] == pytest.approx(0.1, rel=0.02)
    assert err["max_mm"] == pytest.approx(0.1, rel=0.02)


def test_tracking_error_sees_missing_ink():
    command = [np.column_stack([np.linspace(0, 2, 200), np.zeros(200)])]
    half = [command[0][:100]]  # the second centimetre was never inked
    err = tracking_error(command, half)
    assert err["command_to_ink_max_mm"] == pytest.approx(10.0, rel=0.02)
    assert err["ink_to_command_max_mm"] == pytest.approx(0.0, abs=1e-12)


def test_max_ink_gap_finds_a_hole_in_the_ink_and_an_uninked_stroke():
    line = np.column_stack([np.linspace(0, 1, 101), np.zeros(101)])
    ink = np.concatenate([line[:40], line[60:]])
    assert max_ink_gap([line], ink, np.zeros(len(ink))) == pytest.approx(0.21)
    assert max_ink_gap([line], line, np.zeros(len(line))) == pytest.approx(0.01)
    assert max_ink_gap([line, line + 5], line, np.zeros(len(line))) == pytest.approx(1.0)


def test_min_jerk_rests_at_both_ends():
    s = min_jerk(101)
    assert s[0] == 0 and s[-1] == 1 and np.all(np.diff(s) >= 0)
    v = np.diff(s)
    assert v[0] < 1e-4 and v[-1] < 1e-4


def test_plan_writes_each_word_as_a_stroke_with_pen_up_moves_around_it():
    word, _ = _two_words()
    from prg.pipeline.timing import rest_to_rest_samples

    samples, duration = rest_to_rest_samples(word.points, 2.0, 0.3, 60)
    t = np.linspace(0, duration, len(samples))
    down = pen_down_samples(word.points, word.segment, word.segment_kinds, samples)
    settings = MotionSettings(lift_cm=1.5, approach_s=1.0, lower_s=0.5, lift_s=0.5, dwell_s=0.2)
    home = np.array([0.0, -10.0, 20.0])
    plan = plan_motion(samples, t, down, home, settings, dt=1 / 60)

    assert np.all(np.diff(plan.t) > 0)
    assert_allclose(plan.tip[0], home) and assert_allclose(plan.tip[-1], home)
    assert plan.n_strokes == 2
    names = [PHASES[i] for i in plan.phase]
    collapsed = [n for i, n in enumerate(names) if i == 0 or n != names[i - 1]]
    assert collapsed == [
        "approach",
        *["lower", "dwell", "write", "lift"],
        "travel",
        *["lower", "dwell", "write", "lift"],
        "retreat",
    ]
    # the pen touches the paper only from lowering to lifting, and writes at the DMP's times
    assert np.all(plan.tip[plan.pen_down, 2] == 0.0)
    assert np.all(plan.tip[np.isin(plan.phase, [0, 5, 6]), 2] > 1.0 - 1e-9)
    strokes = plan.strokes()
    assert_allclose(np.concatenate(strokes), samples[down])
    for k, (a, b) in enumerate(runs(down)):
        assert_allclose(np.diff(plan.t[plan.pen_down & (plan.stroke == k)]), np.diff(t[a:b]))


def test_plan_refuses_a_word_without_pen_down_samples():
    with pytest.raises(UsageError, match="no pen-down"):
        plan_motion(
            np.zeros((3, 2)), np.arange(3.0), np.zeros(3, bool), np.zeros(3), MotionSettings(), 0.1
        )


def test_word_samples_follow_the_dmp_at_its_tempo():
    from prg.sim import font_word, word_samples

    word = font_word("ab")
    samples, t, down = word_samples(word, dt=1 / 60)
    assert t[-1] == pytest.approx(word.dmp.tau) and down.all()
    assert np.diff(t).max() == pytest.approx(1 / 60, rel=0.05)
    assert distance_to_polylines(samples, [word.points]).max() < 0.01  # within 0.1 mm
    slow, t2, _ = word_samples(word, dt=2 / 60, tempo=2.0)
    assert t2[-1] == pytest.approx(2 * word.dmp.tau)
    assert_allclose(slow, samples, atol=1e-9)  # same samples, twice the time


def test_a_word_without_a_dmp_is_followed_at_its_speed():
    from dataclasses import replace

    from prg.sim import font_word, word_samples

    word = replace(font_word("ab"), dmp=None, duration_s=None)
    samples, t, _ = word_samples(word, dt=1 / 100)
    assert t[-1] == pytest.approx(word.path_length / word.speed_cm_s)
    assert_allclose(samples[[0, -1]], word.points[[0, -1]], atol=1e-9)
