"""Tests of ``studies.stimuli.robot`` (moved from the suite on: stimuli: reading robot and human
samples, and drawing every one of them alike)."""

from __future__ import annotations

import pytest

from prg.errors import UsageError
from prg.pipeline.word import WordTrajectory
from studies.design import ROBOT
from studies.stimuli import (
    generate_robot_words,
    load_robot_words,
    render_sample,
)
from tests.helpers.browser import robot_dir
from tests.helpers.study_stimuli import STYLE


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
    # the body's strokes (one, and one more where the pen lifts within the word), then the marks
    body = kinds.count("space") + 1
    assert len(robot.delayed) == kinds.count("mark") == len(robot.strokes) - body
