"""Tests of ``prg.sim.geometry`` (moved from the suite on: the simulated robot writes: accuracy,
ink, lifts between words, workspace, IK, both arms, outputs, and the Rerun recording read back
from disk)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from numpy.testing import assert_allclose

from prg.errors import SettingsError, UsageError
from prg.recording import read_component, read_times
from prg.sim import (
    Paper,
    font_word,
)
from prg.sim.geometry import (
    bounding_box,
    distance_to_polylines,
    in_contact,
    max_ink_gap,
    pen_down_samples,
    place_points,
    runs,
    tracking_error,
)
from tests.helpers.sim import panda_hi, recording  # noqa: F401 (fixtures)
from tests.helpers.sim_geometry import _two_words


def test_the_ink_lands_where_the_word_was_placed(panda_hi):
    r = panda_hi
    low, high = bounding_box(np.concatenate(r.ink_strokes()))
    assert_allclose((low + high) / 2, r.placement["centre_cm"], atol=0.01)
    assert_allclose(high - low, [r.placement["width_cm"], r.placement["height_cm"]], atol=0.01)


def test_the_dot_is_inked_above_the_stem_after_a_pen_lift(panda_hi):
    r = panda_hi
    word_ink, dot_ink = r.ink_strokes()
    # on the paper the word is placed centred and scaled: map the word's own dot there
    word = font_word("hi")
    (dot,) = [word.segment_points(k) for k, kind in enumerate(word.segment_kinds) if kind == "mark"]
    low, high = bounding_box(word.points)
    scale, centre = r.placement["scale"], np.asarray(r.placement["centre_cm"])
    expected = (dot - (low + high) / 2) * scale + centre
    assert_allclose(dot_ink.mean(axis=0), expected.mean(axis=0), atol=0.02)
    assert dot_ink[:, 1].min() > word_ink[:, 1].max() - 0.5 * (high - low)[1]  # above the stem
    # between the two strokes the pen is in the air
    first_end = np.flatnonzero(r.step_stroke == 0)[-1]
    second_start = np.flatnonzero(r.step_stroke == 1)[0]
    assert r.tip_paper[first_end + 1 : second_start, 2].max() > 1.0


def test_ink_is_logged_once_per_inked_step_not_as_a_whole_line_per_frame(recording, panda_hi):
    r = panda_hi
    inked_steps = sum(b - a - 1 for a, b in runs(r.contact))
    times = read_times(recording, "world/ink", "sim_time")
    assert len(times) == inked_steps
    rows = read_component(recording, "page/ink", "LineStrips2D:strips", timeline="sim_time")
    assert all(len(row) == 1 and len(row[0]) == 2 for row in rows)  # one segment per row
    first = np.asarray(rows[0][0])
    a = runs(r.contact)[0][0]
    assert_allclose(first, r.tip_paper[a : a + 2, :2] * [1, -1], atol=1e-4)


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
    with pytest.raises(
        SettingsError, match=r"^size_cm\[0\] must be a finite number in \(0, 1000\]"
    ) as err:
        Paper(size_cm=(0.0, 10.0))
    assert err.value.field == "size_cm[0]"
    from prg.sim import SimSettings

    with pytest.raises(UsageError, match=r"^paper\.size_cm\[0\] must be a finite number in \(0, "):
        SimSettings.from_mapping({"paper": {"size_cm": [0.0, 10.0]}})


def test_place_points_scales_about_the_anchor_and_moves_it_to_the_target():
    out = place_points([[1.0, 1.0], [3.0, 1.0]], anchor=[2.0, 1.0], scale=2.0, target=[0.0, 5.0])
    assert_allclose(out, [[-2.0, 5.0], [2.0, 5.0]])


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
