"""Sizing and placement of letters on the baseline (final processing map, steps 1-3)."""

from __future__ import annotations

import itertools
import re

import numpy as np
import pytest

from prg.checks import check_values
from prg.data.preprocess import normalise, resample_arclength
from prg.errors import SettingsError, UsageError
from prg.pipeline.layout import (
    LayoutSettings,
    layout_letters,
    letter_band,
    place_letter,
    word_breaks,
)
from tests.conftest import letter_like
from tests.helpers.word import letters_cm, word  # noqa: F401 (fixtures)

P = LayoutSettings()


H = P.letter_height


def letter(seed: int, aspect: float | None = 0.8) -> np.ndarray:
    """A normalised random letter (100 points, y up); ``aspect`` = width / height when given."""
    pts = normalise(resample_arclength(letter_like(np.random.default_rng(seed), 80), 100))
    if aspect is not None:
        ext = np.ptp(pts, axis=0)
        pts = normalise(pts * [aspect / ext[0], 1.0 / ext[1]])
    return pts


def box(points: np.ndarray) -> tuple[float, float, float, float]:
    (x0, y0), (x1, y1) = points.min(axis=0), points.max(axis=0)
    return float(x0), float(y0), float(x1), float(y1)


def test_x_height_letters_are_half_the_height_of_uppercase():
    placed = layout_letters([letter(0), letter(1), letter(2)], "Aax")
    heights = [box(p)[3] - box(p)[1] for p in placed]
    assert heights[0] == pytest.approx(H)
    assert heights[1] == pytest.approx(P.x_height * H)
    assert heights[2] == pytest.approx(heights[0] / 2)


@pytest.mark.parametrize("char", list("ABZ0789bdhklt"))
def test_uppercase_digits_and_ascenders_stand_full_height_on_the_baseline(char):
    _, y0, _, y1 = box(place_letter(letter(3), char, 0.0))
    assert y0 == pytest.approx(0.0, abs=1e-12)
    assert y1 == pytest.approx(H)


@pytest.mark.parametrize("char", list("gjpqy"))
def test_descenders_reach_below_the_baseline(char):
    _, y0, _, y1 = box(place_letter(letter(4), char, 0.0))
    assert y0 == pytest.approx(-P.descender * H)
    assert y1 == pytest.approx(P.x_height * H)


def test_f_is_both_ascender_and_descender():
    assert letter_band("f") == pytest.approx((-P.descender * H, H))
    _, y0, _, y1 = box(place_letter(letter(5), "f", 0.0))
    assert (y0, y1) == pytest.approx((-P.descender * H, H))
    print_f = LayoutSettings(descenders="gjpqy")
    assert letter_band("f", print_f) == pytest.approx((0.0, H))


@pytest.mark.parametrize("char", list("aceimnorsuvwxz"))
def test_x_height_letters_sit_on_the_baseline(char):
    assert letter_band(char) == pytest.approx((0.0, P.x_height * H))


def test_letters_are_placed_left_to_right_a_fixed_gap_apart_without_overlap():
    text = "Hello42world"
    placed = layout_letters([letter(s) for s in range(len(text))], text)
    boxes = [box(p) for p in placed]
    assert boxes[0][0] == pytest.approx(0.0)
    for (_, _, right, _), (left, _, _, _) in itertools.pairwise(boxes):
        assert left - right == pytest.approx(P.gap)
        assert left > right


def test_each_space_adds_the_space_width():
    text = " ab  c "
    placed = layout_letters([letter(1), letter(2), letter(3)], text)
    (_, _, b_right, _), (c_left, _, _, _) = box(placed[1]), box(placed[2])
    assert c_left - b_right == pytest.approx(P.gap + 2 * P.space_width)
    assert box(placed[0])[0] == pytest.approx(0.0)  # a leading space is ignored


def test_scaling_keeps_the_aspect_ratio():
    pts = letter(6, aspect=None)
    placed = place_letter(pts, "k", 1.0)
    scale = np.ptp(placed, axis=0) / np.ptp(pts, axis=0)
    assert scale[0] == pytest.approx(scale[1])
    np.testing.assert_allclose((placed - placed[0]) / scale[0], pts - pts[0], atol=1e-12)


def test_a_very_wide_letter_is_limited_to_the_maximum_width():
    flat = letter(7, aspect=6.0)
    x0, y0, x1, y1 = box(place_letter(flat, "m", 0.0))
    assert x1 - x0 == pytest.approx(P.max_width * H)
    assert y1 - y0 < P.x_height * H
    assert y0 == pytest.approx(0.0, abs=1e-12)


def test_a_horizontal_stroke_is_sized_by_the_width_guard():
    line = np.column_stack([np.linspace(-1, 1, 10), np.zeros(10)])
    x0, y0, x1, y1 = box(place_letter(line, "a", 0.0))
    assert (x1 - x0, y1 - y0) == pytest.approx((P.max_width * H, 0.0))


@pytest.mark.parametrize("n", [1, 5])
def test_a_letter_with_no_extent_is_refused(n):
    """One point is a letter of the right shape, refused for its extent like a still pen."""
    with pytest.raises(UsageError, match="letter 'a' has zero extent"):
        place_letter(np.zeros((n, 2)), "a", 0.0)
    with pytest.raises(UsageError, match=r"letter 'a' must have shape \(n, 2\), got \(0, 2\)"):
        place_letter(np.zeros((0, 2)), "a", 0.0)


def test_letter_count_must_match_the_text():
    with pytest.raises(UsageError, match="has 3 characters but 2 letter trajectories"):
        layout_letters([letter(0), letter(1)], "a bc")


def test_unsupported_characters_are_named():
    with pytest.raises(UsageError, match=r"unsupported characters '!'"):
        layout_letters([letter(0), letter(1)], "a!")
    with pytest.raises(UsageError, match=r"unsupported characters '!', '#': accepted are"):
        layout_letters([letter(0), letter(1), letter(2)], "a!#")


def test_bad_layout_values_are_named():
    with pytest.raises(UsageError, match="letter_height must be a finite number in"):
        LayoutSettings(letter_height=0.0)
    with pytest.raises(UsageError, match=r"gap must be a finite number in \(0, 100\]"):
        LayoutSettings(gap=-0.1)
    with pytest.raises(SettingsError) as caught:  # the field, not a config path
        LayoutSettings(max_width=-1.0)
    assert str(caught.value) == "max_width must be a finite number in (0, 100], got -1.0"
    assert str(caught.value.under("layout")).startswith("layout.max_width ")


@pytest.mark.parametrize("field", ["gap", "descender", "space_width", "x_height"])
def test_the_settings_refuse_what_the_config_refuses(field):
    # the config's range (layout.* in (0, 100]) is the class's: 0 and sizes over 100 are refused
    for value in (0.0, 100.5):
        with pytest.raises(SettingsError, match=rf"^{field} must be a finite number in \(0, 100\]"):
            LayoutSettings(**{field: value})
        with pytest.raises(UsageError, match=rf"^layout\.{field} must be a finite number in"):
            check_values({"layout": {field: value}})


def test_word_breaks_mark_pairs_separated_by_spaces():
    assert word_breaks("ab cd") == [False, True, False]
    assert word_breaks("  a  b ") == [True]
    assert word_breaks("x") == []


# ---- non-default parameters ------------------------------------------------------------------
# The tests above use LayoutSettings(); a formula that reads a default where it should read the
# parameter is invisible there. Here every field differs from its default and the expected boxes
# come from the rules of the module docstring, written out below.

CUSTOM = [
    LayoutSettings(
        letter_height=2.3,
        x_height=0.62,
        descender=0.3,
        max_width=1.1,
        gap=0.35,
        space_width=0.9,
        ascenders="bdhkl",
        descenders="gjpqyz",
    ),
    LayoutSettings(
        letter_height=0.8,
        x_height=0.4,
        descender=0.6,
        max_width=2.4,
        gap=0.01,
        space_width=0.25,
        ascenders="bdfhkltz",
        descenders="fgy",
    ),
]


def expected_band(char: str, p: LayoutSettings) -> tuple[float, float]:
    full = char.isupper() or char.isdigit() or char in p.ascenders
    top = p.letter_height * (1.0 if full else p.x_height)
    bottom = -p.descender * p.letter_height if char in p.descenders else 0.0
    return bottom, top


@pytest.mark.parametrize("params", CUSTOM, ids=["tall-narrow", "short-wide"])
def test_non_default_parameters_give_the_documented_bands_sizes_and_spacing(params):
    text = "Bat fizz  yq7 Ltd"
    chars = [c for c in text if c != " "]
    aspects = [0.3, 0.8, 1.5, 2.7, 4.0]  # some wider than max_width allows
    letters = [letter(20 + i, aspect=aspects[i % len(aspects)]) for i in range(len(chars))]
    placed = layout_letters(letters, text, params)
    assert len(placed) == len(chars)
    right = None
    spaces = [len(m.group(1)) for m in re.finditer(r"( *)[^ ]", text)]  # before each letter
    gaps = [params.gap + params.space_width * n for n in spaces]
    for k, (char, pts, out) in enumerate(zip(chars, letters, placed)):
        bottom, top = expected_band(char, params)
        assert letter_band(char, params) == pytest.approx((bottom, top))
        w, h = np.ptp(pts, axis=0)
        scale = min((top - bottom) / h, params.max_width * params.letter_height / w)
        x0, y0, x1, y1 = box(out)
        assert (y0, y1 - y0, x1 - x0) == pytest.approx((bottom, h * scale, w * scale), rel=1e-12)
        # the shape is only scaled (aspect kept) and translated
        np.testing.assert_allclose(out - out[0], (pts - pts[0]) * scale, atol=1e-12)
        want_left = 0.0 if right is None else right + gaps[k]
        assert x0 == pytest.approx(want_left, abs=1e-12)
        right = x1


def test_a_custom_ascender_set_replaces_the_default_one():
    p = LayoutSettings(ascenders="a", descenders="")
    assert letter_band("a", p) == pytest.approx((0.0, p.letter_height))
    assert letter_band("t", p) == pytest.approx((0.0, p.x_height * p.letter_height))
    assert letter_band("g", p) == pytest.approx((0.0, p.x_height * p.letter_height))


def test_tiny_gap_descender_and_space_width_leave_letters_touching():
    tiny = 1e-9  # the smallest sizes are just above 0 (0 is refused, as by the config)
    p = LayoutSettings(gap=tiny, descender=tiny, space_width=tiny)
    placed = layout_letters([letter(1), letter(2), letter(3)], "g a b", p)
    boxes = [box(q) for q in placed]
    assert boxes[0][1] == pytest.approx(0.0, abs=1e-8)  # no descender depth to speak of
    for (_, _, right, _), (left, _, _, _) in itertools.pairwise(boxes):
        assert left == pytest.approx(right, abs=1e-8)  # no gap, and spaces add next to nothing


def test_malformed_characters_and_letters_are_refused():
    for bad in ("ab", "", "!"):
        with pytest.raises(UsageError, match="unsupported character"):
            letter_band(bad)
    for shape in [(3, 3), (0, 2), (4,)]:
        with pytest.raises(UsageError, match="must have shape"):
            place_letter(np.ones(shape), "a", 0.0)


def test_letters_x_at_either_end_of_the_text_are_laid_out():
    # only spaces are stripped from the ends of the text
    placed = layout_letters([letter(4), letter(5), letter(6)], " Xa X ")
    assert len(placed) == 3
    assert box(placed[0])[0] == pytest.approx(0.0)


def test_every_letter_is_written_whole_and_in_order(word):
    placed = letters_cm()
    assert [c for c, _ in word.letters] == list("abcd")
    for (_, pts), expected in zip(word.letters, placed):
        np.testing.assert_array_equal(pts, expected)
