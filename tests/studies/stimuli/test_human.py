"""Tests of ``studies.stimuli.human`` (moved from the suite on: stimuli: reading robot and human
samples, and drawing every one of them alike)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from prg.errors import UsageError
from prg.pipeline.word import WordTrajectory
from studies.stimuli import (
    load_human_samples,
    render_sample,
    to_pixels,
)
from tests.helpers.browser import capture_document, wobbly_word
from tests.helpers.study_stimuli import STYLE


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
