"""Connections that join letters as a hand does: what a connection may and may not do."""

from __future__ import annotations

import itertools
import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from prg.pipeline.connect import ConnectionSettings, connect_letters
from prg.pipeline.joins import hand_connection, ink_crossings, overshoot, self_crossings
from tests.helpers.joins import _arc

DELTA = ConnectionSettings().delta


def _path(prev, result, nxt):
    return np.concatenate([prev[-1:], result.points, nxt[:1]])


def test_crossings_count_ink_cut_away_from_the_ends_only():
    stem = np.array([[1.0, -1.0], [1.0, 1.0]])
    through = np.array([[0.0, 0.0], [2.0, 0.0]])
    assert ink_crossings(through, [stem]) == 1
    assert ink_crossings(through, [stem, stem + np.array([0.5, 0.0])]) == 2
    # a stroke that leaves a letter's ink where it starts is not cutting it
    leaving = np.array([[1.0, 0.0], [2.0, 0.0]])
    assert ink_crossings(leaving, [np.array([[0.95, -1.0], [1.05, 1.0]])]) == 0
    # touching is not crossing
    assert (
        ink_crossings(np.array([[0.0, 0.0], [1.0, 0.0]]), [np.array([[1.0, 0.0], [1.0, 1.0]])]) == 0
    )


def test_a_connection_that_crosses_no_ink_is_algorithm_1s():
    prev = _arc((0.0, 0.25), (0.25, 0.25), 180, 360 + 0)  # ends at its right, on the baseline
    nxt = _arc((1.0, 0.25), (0.25, 0.25), 180, 540)  # starts at its left
    alg1 = connect_letters(prev, nxt, **ConnectionSettings().as_kwargs())
    assert ink_crossings(_path(prev, alg1, nxt), [prev, nxt]) == 0
    mine = hand_connection(prev, nxt, [prev, nxt])
    np.testing.assert_array_equal(mine.points, alg1.points)


def test_an_o_entered_at_its_top_is_not_cut_through():
    """Algorithm 1 climbs from the baseline through the o to its top; the hand's stroke does
    not cross it."""
    prev = np.column_stack([np.linspace(-0.6, -0.1, 30), np.zeros(30)])  # ends on the baseline
    o = _arc((0.4, 0.25), (0.3, 0.25), 80, 80 + 360)  # starts near its top, counter-clockwise
    alg1 = connect_letters(prev, o, **ConnectionSettings().as_kwargs())
    mine = hand_connection(prev, o, [prev, o])
    assert ink_crossings(_path(prev, mine, o), [prev, o]) == 0
    assert ink_crossings(_path(prev, alg1, o), [prev, o]) >= ink_crossings(
        _path(prev, mine, o), [prev, o]
    )


def test_an_o_left_at_its_top_is_bridged_to_the_next_letter_not_looped_over():
    """Algorithm 1 leaves the o heading left, as its last stroke does, and swings round above
    both letters; the hand's stroke turns at the o's top and bridges across, in their band."""
    o = _arc((0.0, 0.37), (0.3, 0.37), 90, 450)  # counter-clockwise, closes at its top
    stem = np.column_stack([np.linspace(0.55, 0.75, 30), np.linspace(0.74, 0.0, 30)])
    clearance = 0.1 + 0.1 * np.linalg.norm(stem[0] - o[-1])
    alg1 = connect_letters(o, stem, **ConnectionSettings().as_kwargs())
    assert overshoot(_path(o, alg1, stem), o, stem) > clearance  # the case is the loop's
    path = _path(o, hand_connection(o, stem, [o, stem]), stem)
    assert ink_crossings(path, [o, stem]) == self_crossings(path) == 0
    assert overshoot(path, o, stem) <= clearance


def test_an_arch_into_an_o_clears_the_o_not_the_ascender_before_it():
    """An l ends at its foot; the o after it starts at its top left, so the straight way in
    cuts the o. The stroke arches over the o at the o's height, not over the l's loop (the
    demo's "hello" rose higher than the l between its last two letters)."""
    up = np.column_stack([np.linspace(0.0, 0.25, 40), np.linspace(0.0, 1.5, 40)])
    down = np.column_stack([np.linspace(0.25, 0.3, 30), np.linspace(1.5, 0.0, 30)])
    ell = np.concatenate([up, down])
    o = _arc((1.0, 0.35), (0.35, 0.35), 120, 480)
    assert ink_crossings(np.stack([ell[-1], o[0]]), [o]) > 0  # the straight way in cuts it
    path = _path(ell, hand_connection(ell, o, [ell, o]), o)
    assert ink_crossings(path, [ell, o]) == 0
    assert path[:, 1].max() < 0.7 + 0.25 < 1.5  # just over the o, well under the l's top


def test_no_clean_join_means_the_pen_is_lifted():
    """A letter that ends inside its own closed ink: every stroke to the next letter cuts it.
    Asked to, the hand method lifts the pen instead (a straight pen-up travel)."""
    from prg.pipeline.connect import connect_sequence

    box = _polyline((0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.0, 0.1), (0.55, 0.5))
    nxt = _arc((1.8, 0.37), (0.3, 0.37), 150, 510)
    joined = hand_connection(box, nxt, [box, nxt])
    assert not joined.pen_up and ink_crossings(_path(box, joined, nxt), [box, nxt]) > 0
    lifted = hand_connection(box, nxt, [box, nxt], lift=True)
    assert lifted.pen_up
    assert connect_sequence([box, nxt], method="hand")[0].pen_up
    assert not connect_sequence([box, nxt], method="alg1")[0].pen_up  # the paper never lifts


@st.composite
def round_letter_pairs(draw):
    """Two round letters side by side: arcs of 300 degrees either way, any exit and entry, the
    second a little apart and higher or lower."""
    size, gap, rise = (
        draw(st.floats(0.2, 0.5)),
        draw(st.floats(0.05, 0.8)),
        draw(st.floats(-0.4, 0.6)),
    )
    exit_deg, entry_deg = draw(st.floats(-180, 180)), draw(st.floats(-180, 180))
    turn = draw(st.sampled_from([-300, 300]))
    prev = _arc((0.0, size), (size, size), exit_deg - turn, exit_deg)
    nxt = _arc((2 * size + gap, size + rise), (size, size), entry_deg, entry_deg + turn)
    return prev, nxt


@settings(max_examples=80, deadline=None)
@given(pair=round_letter_pairs())
def test_a_connection_may_bend_but_never_leaves_a_gap_nor_cuts_more_than_algorithm_1(pair):
    """Any two round letters side by side: the connection starts where the first ends, ends
    where the second starts, leaves no gap wider than delta, and crosses no more ink than the
    paper's Algorithm 1 would."""
    prev, nxt = pair
    result = hand_connection(prev, nxt, [prev, nxt])
    path = _path(prev, result, nxt)
    steps = np.linalg.norm(np.diff(path, axis=0), axis=1)
    assert steps.max() <= DELTA * (1 + 1e-9)
    alg1 = connect_letters(prev, nxt, **ConnectionSettings().as_kwargs())
    assert ink_crossings(path, [prev, nxt]) <= ink_crossings(_path(prev, alg1, nxt), [prev, nxt])


@settings(max_examples=60, deadline=None)
@given(
    gap=st.floats(0.1, 0.8),
    rise=st.floats(-0.2, 0.2),
    exit_deg=st.floats(-80, -5),
    entry_deg=st.floats(185, 250),
    size=st.floats(0.2, 0.5),
)
def test_letters_that_face_each_other_are_joined_without_cutting_either(
    gap, rise, exit_deg, entry_deg, size
):
    """The first letter ends on its right side heading right (drawn counter-clockwise to a
    point below its middle), the second starts on its lower left heading down or right, on
    about one line: the connection crosses neither. Not claimed: a next letter entered at its
    top heading left between two letters a tenth of their size apart (the stroke would have to
    thread the gap; hypothesis finds such cases), where the connection only crosses no more
    than Algorithm 1's (the test above)."""
    prev = _arc((0.0, size), (size, size), exit_deg - 300, exit_deg)
    nxt = _arc((2 * size + gap, size + rise), (size, size), entry_deg, entry_deg + 300)
    result = hand_connection(prev, nxt, [prev, nxt])
    assert ink_crossings(_path(prev, result, nxt), [prev, nxt]) == 0


@settings(max_examples=60, deadline=None)
@given(pair=round_letter_pairs())
def test_the_hand_method_joins_cleanly_or_lifts_the_pen(pair):
    """Any two round letters side by side, joined by the default method: either the pen lifts,
    or the stroke crosses no ink, does not loop and stays within an arch's clearance of the band
    the two letters span."""
    from prg.pipeline.connect import connect_sequence

    prev, nxt = pair
    (result,) = connect_sequence([prev, nxt], method="hand")
    if result.pen_up:
        return
    path = _path(prev, result, nxt)
    assert ink_crossings(path, [prev, nxt]) == self_crossings(path) == 0
    clearance = 0.1 + 0.1 * max(np.linalg.norm(nxt[0] - prev[-1]), DELTA)
    assert overshoot(path, prev, nxt) <= clearance


def test_the_turn_into_the_next_letter_follows_its_first_stroke():
    """A candidate curve enters the next letter along its first step (no kink at the join)."""
    prev = np.column_stack([np.linspace(-0.6, 0.0, 30), np.zeros(30)])
    wall = np.array([[0.3, -0.5], [0.3, 1.0]])  # ink between the letters: Algorithm 1 cuts it
    nxt = np.column_stack([np.full(30, 0.9), np.linspace(0.8, 0.0, 30)])  # a stem, top down
    result = hand_connection(prev, nxt, [prev, wall, nxt])
    assert result.steered == 0  # not Algorithm 1's: it crossed the wall
    last = nxt[0] - result.points[-1]
    heading = math.degrees(math.atan2(last[1], last[0]))
    assert -150 < heading < -30  # coming down into the stem


def _o_descending_after_closing():
    """An o from its top right, round anticlockwise back up near its start, then down its right
    side into a low exit (the shape that read as an a)."""
    angle = np.linspace(0.5 * np.pi, 2.4 * np.pi, 60)
    loop = np.column_stack([0.5 + 0.5 * np.cos(angle), 0.5 + 0.5 * np.sin(angle)])
    tail = np.column_stack([np.linspace(loop[-1, 0], 1.3, 40), np.linspace(loop[-1, 1], 0.2, 40)])
    return np.vstack([loop, tail[1:]])


def test_an_o_that_descends_after_closing_is_left_at_its_top():
    from prg.pipeline.joins import CLOSED_NEAR, closed_exit

    o = _o_descending_after_closing()
    cut = closed_exit(o)
    assert len(cut) < len(o) and np.array_equal(cut, o[: len(cut)])
    height = np.ptp(o[:, 1])
    assert np.linalg.norm(cut[-1] - o[0]) < CLOSED_NEAR * height  # where it closes
    assert cut[-1, 1] > o[:, 1].min() + 0.5 * height  # in its upper half, not at the exit


def test_an_o_that_ends_where_it_closes_or_never_closes_is_kept_whole():
    from prg.pipeline.joins import closed_exit

    o = _o_descending_after_closing()
    closes = o[:60]
    assert np.array_equal(closed_exit(closes), closes)
    angle = np.linspace(0.5 * np.pi, 1.6 * np.pi, 60)  # a c: never comes back to its start
    c = np.column_stack([np.cos(angle), np.sin(angle)])
    assert np.array_equal(closed_exit(c), c)


def test_only_the_hand_method_leaves_an_o_at_its_top():
    from prg.pipeline.compose import GenerateSettings, compose_word

    o = _o_descending_after_closing()
    o = np.array(
        [np.interp(np.linspace(0, 1, 100), np.linspace(0, 1, len(o)), o[:, k]) for k in (0, 1)]
    ).T
    letters = np.stack([o, o])
    hand = compose_word(letters, "oo", GenerateSettings(method="hand"))[0]
    paper = compose_word(letters, "oo", GenerateSettings(method="alg1"))[0]
    first = lambda word: word.points[word.segment == 0]  # noqa: E731
    last = lambda word: word.points[word.segment == 2]  # noqa: E731
    assert len(first(hand)) < len(first(paper)) == 100
    assert len(last(hand)) == len(last(paper)) == 100  # the word's last o keeps its exit


def _polyline(*corners, n=40):
    """Points every so often along straight pieces through ``corners``."""
    pieces = [np.linspace(a, b, n, endpoint=False) for a, b in itertools.pairwise(corners)]
    return np.concatenate([*pieces, np.array(corners[-1:], dtype=float)])


# a print j: its stem down from the x-height, its foot curling left below the baseline
PRINT_J = _polyline((0.0, 0.75), (0.0, -0.4), (-0.15, -0.6), (-0.35, -0.5))
# a cursive j: the same stem, its tail looping back up past the stem to the baseline
CURSIVE_J = _polyline((0.0, 0.75), (0.0, -0.4), (-0.2, -0.6), (-0.3, -0.4), (0.35, 0.0))
NEXT_O = _arc((0.9, 0.37), (0.3, 0.37), 90, 450)  # an o to the right, started at its top


def test_a_print_descender_is_left_by_lifting_the_pen():
    from prg.pipeline.joins import lifts_pen

    assert lifts_pen(PRINT_J, NEXT_O)  # the line to the o crosses the j's stem
    assert not lifts_pen(CURSIVE_J, NEXT_O)  # it leaves past its stem, towards the o


def test_only_a_letter_ending_left_of_its_middle_that_must_go_back_over_itself_lifts():
    from prg.pipeline.joins import lifts_pen

    o = _arc((0.0, 0.37), (0.3, 0.37), 90, 450)  # ends where it started, at its top middle
    assert not lifts_pen(
        o, NEXT_O + np.array([0.0, -0.45])
    )  # the line leaves through its right side
    slash = _polyline((0.5, 0.75), (0.0, 0.0))  # ends at its left, nothing between it and the o
    assert not lifts_pen(slash, NEXT_O + np.array([0.3, 0.0]))
    hook = _polyline((0.5, 0.75), (0.0, 0.0), (0.5, 0.3), (0.1, 0.3))  # ends left, inside itself
    assert lifts_pen(hook, NEXT_O + np.array([0.3, 0.0]))


def test_a_letter_that_starts_on_its_far_side_is_entered_by_lifting_the_pen():
    """A print a starts at its top right: from a letter on its left the way in goes round or
    through its bowl. An o started at its top middle or left is joined."""
    from prg.pipeline.joins import START_FAR, lifts_pen

    foot = _polyline((-0.4, 0.75), (-0.4, 0.0), (0.0, 0.0))  # ends on the baseline, heading right
    a = _arc((1.0, 0.37), (0.3, 0.37), 30, 360)
    assert (a[0, 0] - a[:, 0].min()) / np.ptp(a[:, 0]) > START_FAR
    assert lifts_pen(foot, a)
    for start_deg in (90, 150):
        assert not lifts_pen(foot, _arc((1.0, 0.37), (0.3, 0.37), start_deg, start_deg + 360))


def test_the_hand_method_lifts_the_pen_after_a_print_descender_and_only_it():
    from prg.pipeline.connect import connect_sequence
    from prg.pipeline.word import assemble_word

    letters = [PRINT_J, NEXT_O]
    for method in ("alg1", "straight"):  # the paper's joins never lift
        (joined,) = connect_sequence(letters, method=method)
        assert not joined.pen_up
    (lifted,) = connect_sequence(letters, method="hand")
    assert lifted.pen_up
    word = assemble_word(letters, [lifted], "jo")
    assert word.segment_kinds == ["letter", "space", "letter"]
    travel = word.points[word.segment == 1]
    assert not word.pen_down()[word.segment == 1].any()  # drawn without ink
    # a straight travel, from the j's foot to the o's start
    direction = (NEXT_O[0] - PRINT_J[-1]) / np.linalg.norm(NEXT_O[0] - PRINT_J[-1])
    offsets = travel - PRINT_J[-1]
    assert np.allclose(offsets[:, 0] * direction[1] - offsets[:, 1] * direction[0], 0, atol=1e-9)
    (cursive,) = connect_sequence([CURSIVE_J, NEXT_O], method="hand")
    assert not cursive.pen_up
