"""Tests of ``studies.stimuli.render`` (moved from the suite on: stimuli: reading robot and human
samples, and drawing every one of them alike)."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from prg.errors import UsageError
from studies.design import ROBOT
from studies.stimuli import (
    RenderStyle,
    Sample,
    load_robot_words,
    render_sample,
    render_strokes,
    stimulus_name,
    to_pixels,
)
from tests.helpers.browser import wobbly_word
from tests.helpers.study_stimuli import STYLE, marked_word


def ink_box(image: Image.Image, threshold: int = 128) -> tuple[int, int, int, int]:
    """(left, top, right, bottom) of the dark pixels, inclusive."""
    a = np.asarray(image) < threshold
    ys, xs = np.nonzero(a)
    return xs.min(), ys.min(), xs.max(), ys.max()


# ---------------------------------------------------------------------------- rendering
def test_every_stimulus_is_a_fixed_size_grey_png_black_on_white(tmp_path):
    rng = np.random.default_rng(0)
    for word in ("a", "cat", "elephants"):
        image = render_strokes([wobbly_word(word, rng)], STYLE)
        assert image.size == (400, 100) and image.mode == "L"
        a = np.asarray(image)
        assert a.min() < 20 and a[0, 0] == 255  # black ink, white paper


def test_scale_and_place_of_the_writing_leave_no_trace():
    pts = wobbly_word("word", np.random.default_rng(1))
    a = np.asarray(render_strokes([pts], STYLE), dtype=int)
    b = np.asarray(render_strokes([pts * 37.5 + [1000.0, -250.0]], STYLE), dtype=int)
    assert np.abs(a - b).max() <= 2  # same picture up to rounding


def test_tall_words_fill_the_height_and_wide_words_the_width_centred():
    tall = np.array([[0.0, 0.0], [0.5, 2.0], [1.0, 0.0]])
    left, top, right, bottom = ink_box(render_strokes([tall], STYLE))
    assert top == pytest.approx(10, abs=1.5) and bottom == pytest.approx(89, abs=1.5)
    assert (left + right) / 2 == pytest.approx(199.5, abs=1.5)
    wide = np.array([[0.0, 0.0], [10.0, 0.3], [20.0, 0.0]])
    left, top, right, bottom = ink_box(render_strokes([wide], STYLE))
    assert left == pytest.approx(10, abs=1.5) and right == pytest.approx(389, abs=1.5)
    assert (top + bottom) / 2 == pytest.approx(49.5, abs=2)


def test_ink_never_enters_the_margin():
    rng = np.random.default_rng(2)
    for _ in range(5):
        a = np.asarray(render_strokes([rng.normal(size=(50, 2))], STYLE)) < 250
        m = STYLE.margin_px
        assert not a[:m].any() and not a[-m:].any() and not a[:, :m].any() and not a[:, -m:].any()


def test_y_up_input_is_drawn_upright():
    rising = np.array([[0.0, 0.0], [1.0, 1.0]])  # bottom-left to top-right
    a = np.asarray(render_strokes([rising], STYLE)) < 128
    ys, xs = np.nonzero(a)
    assert np.corrcoef(xs, ys)[0, 1] < -0.9  # image rows grow downwards


def test_stroke_width_is_the_same_whatever_the_word_size():
    line = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 0.2]])
    for scale in (0.01, 1.0, 500.0):
        a = np.asarray(render_strokes([line * scale], STYLE)) < 128
        column = a[:, 200]
        assert column.sum() == pytest.approx(4, abs=1)


def test_render_settings_are_checked():
    with pytest.raises(UsageError, match="render: unknown key 'colour'"):
        RenderStyle.from_dict({"colour": "red"})
    with pytest.raises(UsageError, match=r"render.width_px must be an integer from 1 to 4000"):
        RenderStyle(width_px=0)
    with pytest.raises(UsageError, match="no room for the word"):
        RenderStyle(height_px=20, margin_px=10)
    with pytest.raises(UsageError, match="no points"):
        render_sample(Sample("cat", "w1", ()), STYLE)


def test_stimulus_names_reveal_neither_word_nor_writer():
    a = stimulus_name(Sample("cat", ROBOT, ()), "turing:1")
    b = stimulus_name(Sample("cat", "w01", ()), "turing:1")
    assert a != b and a == stimulus_name(Sample("cat", ROBOT, ()), "turing:1")
    assert a != stimulus_name(Sample("cat", ROBOT, ()), "turing:2")
    for name in (a, b):
        assert "cat" not in name and "robot" not in name and "w01" not in name
        assert len(name) == len("0123456789abcdef.png")


def test_robot_words_are_drawn_with_their_dots_above_the_stem(tmp_path):
    marked_word("in").to_json(tmp_path / "in.json")
    robot = load_robot_words(tmp_path, ["in"])["in"]
    assert robot.delayed == (1,) and len(robot.strokes) == 2  # the body, then the i's dot
    image = np.asarray(render_sample(robot, STYLE)) < 128
    body, dot = to_pixels(robot.strokes, STYLE)
    cx, cy = np.round(dot.mean(axis=0)).astype(int)
    column = image[:, cx - 1 : cx + 2].any(axis=1)
    stem = body[np.abs(body[:, 0] - cx) < 2, 1].min()  # the stem's top under the dot
    assert column[cy]  # ink at the dot
    assert not column[cy + 3 : int(stem) - 3].all()  # paper between the dot and the stem
    assert cy < stem - STYLE.stroke_px  # above the stem

    single = load_robot_words(tmp_path, ["in"], delayed_strokes=False)["in"]
    assert len(single.strokes) == 1 and single.delayed == ()
    image = np.asarray(render_sample(single, STYLE)) < 128
    (body,) = to_pixels(single.strokes, STYLE)
    assert not image[: int(body[:, 1].min() - STYLE.stroke_px)].any()  # nothing above the word
