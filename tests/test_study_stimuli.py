"""Stimuli: reading robot and human samples, and drawing every one of them alike."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from prg.errors import UsageError
from prg.pipeline.compose import compose_word
from prg.pipeline.word import WordTrajectory
from studies.design import ROBOT
from studies.stimuli import (
    RenderStyle,
    Sample,
    generate_robot_words,
    load_human_samples,
    load_robot_words,
    path_strokes,
    render_sample,
    render_strokes,
    stand_ins,
    stimulus_name,
    to_pixels,
    trajectory_sample,
    word_strokes,
)
from tests.conftest_browser import capture_document, robot_dir, wobbly_word

STYLE = RenderStyle(width_px=400, height_px=100, margin_px=10, stroke_px=4.0)


def marked_word(text: str) -> WordTrajectory:
    """A word composed as ``prg-write`` composes it (layout, connections, delayed strokes),
    from letters that are each one up-and-down stroke (no model needed)."""
    u = np.linspace(0, 1, 100)
    letter = np.column_stack([0.3 * np.sin(np.pi * u), 1 - 2 * np.abs(2 * u - 1)])
    word, _ = compose_word(np.stack([letter] * len(text)), text)
    return word


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


# ---------------------------------------------------------------------------- human samples
def test_capture_files_give_one_sample_per_word_flipped_to_y_up(tmp_path):
    doc = capture_document("w07", ["cat", "dog"])
    (tmp_path / "c.json").write_text(json.dumps(doc))
    found = load_human_samples([tmp_path], ["cat", "dog"])
    assert found.writers() == {"cat": ["w07"], "dog": ["w07"]}
    sample = found.by_word["cat"]["w07"]
    raw = np.array(doc["samples"][0]["strokes"][0])[:, :2]
    np.testing.assert_allclose(sample.strokes[0], raw * [1, -1])
    assert sample.source == "human" and not sample.lifted and found.notes == []


def test_lifted_skipped_foreign_and_duplicate_samples_are_left_out_with_a_note(tmp_path):
    doc = capture_document("w01", ["cat", "dog", "sun"])
    doc["samples"][1]["strokes"].append([[1, 2, 3, 0.5], [4, 5, 6, 0.5]])  # a pen lift
    doc["samples"].append({"word": "egg", "strokes": [], "skipped": True})
    (tmp_path / "a.json").write_text(json.dumps(doc))
    (tmp_path / "b.json").write_text(json.dumps(capture_document("w01", ["cat"])))
    found = load_human_samples([tmp_path], ["cat", "dog", "egg"])
    assert found.writers() == {"cat": ["w01"], "dog": [], "egg": []}
    notes = "\n".join(found.notes)
    assert "w01/dog was written with a pen lift" in notes
    assert "'sun' is not a study word" in notes
    assert "a second 'cat' by w01" in notes
    kept = load_human_samples([tmp_path], ["dog"], accept_lifted=True)
    assert kept.by_word["dog"]["w01"].lifted
    assert len(kept.by_word["dog"]["w01"].strokes) == 2


def test_dots_and_bars_after_the_word_are_no_pen_lift(tmp_path):
    doc = capture_document("w02", ["it", "cat", "dog"])
    word = np.array(doc["samples"][0]["strokes"][0])
    top = word[:, 1].min()  # y down: the top of the word
    dot = [[100, top - 20, 900, 0.5], [101, top - 21, 910, 0.5]]
    doc["samples"][0]["strokes"].append(dot)
    doc["samples"][0]["delayed"] = [1]
    doc["samples"][1]["strokes"] += [
        dot,
        (word[:30] + np.array([0, 5, 0, 0])).tolist(),
    ]  # dot, then lift
    doc["samples"][1]["delayed"] = [1]
    (tmp_path / "c.json").write_text(json.dumps(doc))
    found = load_human_samples([tmp_path], ["it", "cat", "dog"])
    assert found.writers() == {"it": ["w02"], "cat": [], "dog": ["w02"]}
    sample = found.by_word["it"]["w02"]
    assert not sample.lifted and sample.delayed == (1,) and len(sample.strokes) == 2
    np.testing.assert_allclose(sample.strokes[1], np.array(dot)[:, :2] * [1, -1])
    assert "w02/cat was written with a pen lift" in "\n".join(found.notes)
    assert found.by_word["dog"]["w02"].delayed == ()
    # the picture shows the dot: ink above the word's own top
    a = np.asarray(render_sample(sample, STYLE)) < 128
    word_top = to_pixels(sample.strokes, STYLE)[0][:, 1].min()
    assert a[: int(word_top) - 2].any()
    # the same file without its "delayed" list (written before it existed): a lift, as before
    del doc["samples"][0]["delayed"]
    (tmp_path / "c.json").write_text(json.dumps(doc))
    assert load_human_samples([tmp_path], ["it"]).writers() == {"it": []}


def test_with_delayed_strokes_off_the_dots_of_human_samples_are_not_drawn(tmp_path):
    doc = capture_document("w03", ["it"])
    doc["samples"][0]["strokes"].append([[5, 5, 900, 0.5]])
    doc["samples"][0]["delayed"] = [1]
    (tmp_path / "c.json").write_text(json.dumps(doc))
    found = load_human_samples([tmp_path], ["it"], delayed_strokes=False)
    sample = found.by_word["it"]["w03"]
    assert len(sample.strokes) == 1 and sample.delayed == () and not sample.lifted
    assert "1 delayed stroke(s) (dots, bars) are not drawn" in found.notes[0]
    np.testing.assert_allclose(
        sample.strokes[0], np.array(doc["samples"][0]["strokes"][0])[:, :2] * [1, -1]
    )


@pytest.mark.parametrize("delayed", [[0], [3], ["1"], [1, 1], 1, [True]])
def test_a_bad_delayed_list_is_named(tmp_path, delayed):
    doc = capture_document("w04", ["it"])
    doc["samples"][0]["strokes"].append([[5, 5, 900, 0.5]])
    doc["samples"][0]["delayed"] = delayed
    (tmp_path / "c.json").write_text(json.dumps(doc))
    with pytest.raises(UsageError, match=r"c.json: samples\[0\]: delayed must list strokes"):
        load_human_samples([tmp_path], ["it"])


def test_strokes_json_named_by_its_folder_and_word_trajectories(tmp_path):
    (tmp_path / "anna").mkdir()
    (tmp_path / "anna" / "cat.json").write_text(json.dumps([[[0, 0], [1, 1], [2, 0]]]))
    (tmp_path / "ben.json").write_text(
        json.dumps({"word": "cat", "writer_id": "ben", "strokes": [[[0, 0], [1, 1]]], "y_down": 1})
    )
    traj = WordTrajectory(wobbly_word("dog", np.random.default_rng(0)), [0] * 90, ["letter"], "d")
    traj = WordTrajectory(traj.points, np.repeat([0, 1, 2], 30), ["letter"] * 3, "dog")
    traj.to_json(tmp_path / "anna" / "dog.json")
    found = load_human_samples([tmp_path], ["cat", "dog"])
    assert found.writers() == {"cat": ["anna", "ben"], "dog": ["anna"]}
    np.testing.assert_allclose(found.by_word["cat"]["ben"].strokes[0], [[0, 0], [1, -1]])
    np.testing.assert_allclose(found.by_word["dog"]["anna"].strokes[0], traj.points)


def test_a_file_without_a_writer_is_named_in_the_error(tmp_path):
    (tmp_path / "cat.json").write_text(json.dumps([[[0, 0], [1, 1]]]))
    with pytest.raises(UsageError, match=r"cat.json: no writer_id: put it in the file"):
        load_human_samples([tmp_path], ["cat"])


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("{not json", "not valid JSON"),
        ('{"schema": "prg.handwriting_capture", "version": 9}', "capture version 9"),
        ('{"writer_id": "a", "strokes": [[["x", 1]]]}', r"\[x, y, ...\] numbers"),
    ],
)
def test_broken_human_files_are_named(tmp_path, content, message):
    (tmp_path / "w1").mkdir()
    (tmp_path / "w1" / "cat.json").write_text(content)
    with pytest.raises(UsageError, match=message) as err:
        load_human_samples([tmp_path], ["cat"])
    assert "cat.json" in str(err.value)


def test_missing_human_folder_is_named(tmp_path):
    with pytest.raises(UsageError, match=r"--human .*nope: no such folder"):
        load_human_samples([tmp_path / "nope"], ["cat"])


def test_svg_polylines_and_paths_with_transforms(tmp_path):
    (tmp_path / "eve").mkdir()
    (tmp_path / "eve" / "cat.svg").write_text(
        '<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 50">'
        '<g transform="translate(10, 5)">'
        '<polyline points="0,0 10,10 20,0" fill="none" stroke="black"/>'
        '<path d="M 30 0 l 10 10 h 5 v -5 Z" transform="scale(2)"/>'
        "</g></svg>"
    )
    assert "pen lift" in load_human_samples([tmp_path], ["cat"]).notes[0]
    found = load_human_samples([tmp_path], ["cat"], accept_lifted=True)
    sample = found.by_word["cat"]["eve"]
    assert sample.lifted  # two strokes
    np.testing.assert_allclose(sample.strokes[0], [[10, -5], [20, -15], [30, -5]])
    np.testing.assert_allclose(
        sample.strokes[1], [[70, -5], [90, -25], [100, -25], [100, -15], [70, -5]]
    )


def test_svg_curves_are_sampled_and_pass_through_their_end_points():
    (stroke,) = path_strokes("M0 0 C 0 10 10 10 10 0 S 20 -10 20 0 Q 25 5 30 0 T 40 0", "x")
    for end in ([10, 0], [20, 0], [30, 0], [40, 0]):
        assert np.min(np.hypot(*(stroke - end).T)) < 1e-9
    assert stroke[:, 1].max() == pytest.approx(7.5)  # the cubic's peak
    with pytest.raises(UsageError, match="malformed SVG path data"):
        path_strokes("M 0 0 L 5", "x")


def test_svg_backgrounds_and_shapes_are_not_pen_strokes(tmp_path):
    (tmp_path / "eve").mkdir()
    (tmp_path / "eve" / "cat.svg").write_text(
        '<svg xmlns="http://www.w3.org/2000/svg" width="6cm" height="2cm" viewBox="0 0 6 2">'
        '<rect width="100%" height="100%" fill="#fff"/><circle cx="1" cy="1" r="0.5"/>'
        '<polyline points="1,1 2,1.5 3,1"/></svg>'
    )
    sample = load_human_samples([tmp_path], ["cat"]).by_word["cat"]["eve"]
    assert not sample.lifted  # read in the file's user units: no viewBox scaling
    np.testing.assert_allclose(sample.strokes[0], [[1, -1], [2, -1.5], [3, -1]])


# ---------------------------------------------------------------------------- robot samples
def test_robot_words_are_read_from_either_layout(tmp_path):
    robot_dir(tmp_path / "flat", ["cat", "dog"])
    nested = tmp_path / "nested" / "cat"
    nested.mkdir(parents=True)
    (tmp_path / "flat" / "cat.json").rename(nested / "word.json")
    (tmp_path / "flat" / "dog.json").rename(tmp_path / "nested" / "dog.json")
    robot = load_robot_words(tmp_path / "nested", ["cat", "dog"])
    assert {w: s.writer_id for w, s in robot.items()} == {"cat": ROBOT, "dog": ROBOT}
    with pytest.raises(UsageError, match="no word trajectory for 'sun'"):
        load_robot_words(tmp_path / "nested", ["sun"])
    (nested / "word.json").rename(tmp_path / "nested" / "egg.json")
    with pytest.raises(UsageError, match=r"egg.json: holds 'cat', expected 'egg'"):
        load_robot_words(tmp_path / "nested", ["egg"])


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


def test_pen_up_travel_is_not_ink():
    pts = np.array([[0, 0], [1, 0], [2, 0], [3, 0], [4, 0], [5, 0]], dtype=float)
    traj = WordTrajectory(pts, [0, 0, 1, 1, 2, 2], ["letter", "space", "letter"], "a b")
    strokes = word_strokes(traj)
    assert [s.tolist() for s in strokes] == [[[0, 0], [1, 0]], [[4, 0], [5, 0]]]


def test_robot_words_are_written_by_prg_write(tmp_path, untrained_muse_checkpoint):
    lines = []
    paths = generate_robot_words(
        ["ab", "cd"], tmp_path / "robot", ckpt=untrained_muse_checkpoint, progress=lines.append
    )
    assert sorted(paths) == ["ab", "cd"]
    assert lines == ["robot writes 'ab' (1/2)", "robot writes 'cd' (2/2)"]
    assert sorted(p.name for p in (tmp_path / "robot").iterdir()) == ["ab.json", "cd.json"]
    robot = load_robot_words(tmp_path / "robot", ["ab", "cd"])
    assert [c for c, _ in WordTrajectory.from_json(paths["ab"]).letters] == ["a", "b"]
    assert render_sample(robot["cd"], STYLE).size == (400, 100)


def test_robot_writing_names_a_missing_checkpoint_and_a_bad_override(tmp_path):
    with pytest.raises(UsageError, match=r"nope.ckpt"):
        generate_robot_words(["ab"], tmp_path, ckpt=tmp_path / "nope.ckpt")
    with pytest.raises(UsageError, match=r"robot.write_overrides"):
        generate_robot_words(["ab"], tmp_path, overrides=["generate.nonsense=1"])
    for override in ("delayed_strokes=false", "++delayed_strokes=true"):
        with pytest.raises(UsageError, match=r"delayed_strokes is set by the study's top-level"):
            generate_robot_words(["ab"], tmp_path, overrides=[override])


@pytest.mark.parametrize("delayed", [True, False])
def test_robot_words_are_written_with_delayed_strokes_as_asked(
    tmp_path, untrained_muse_checkpoint, delayed
):
    paths = generate_robot_words(
        ["it"], tmp_path, ckpt=untrained_muse_checkpoint, delayed_strokes=delayed
    )
    kinds = WordTrajectory.from_json(paths["it"]).segment_kinds
    assert kinds.count("mark") == (2 if delayed else 0)  # the i's dot and the t's bar
    robot = load_robot_words(tmp_path, ["it"])["it"]
    assert len(robot.delayed) == kinds.count("mark") == len(robot.strokes) - 1


@pytest.mark.parametrize(
    "overrides",
    [
        [],
        ["generate.temperature=0.3", "generate.mode=posterior"],
        ["generate.hand_seed=3", "layout.gap=0.3", "marks.dotted=j"],
        ["connection.alpha_max_deg=25", "++generate.impute_steps=10"],
    ],
)
def test_the_robot_writes_with_prg_writes_settings(overrides):
    from prg.commands.cli import compose_config
    from prg.commands.settings import generate_settings
    from studies.stimuli import write_settings

    for delayed in (True, False):
        args = ["family=muse", f"delayed_strokes={str(delayed).lower()}", *overrides]
        expected = generate_settings(compose_config("write", args))
        assert write_settings(overrides, delayed).generate == expected
