"""Tests of ``studies.judge`` (moved from the suite on: prg-study judge: a classifier two-sample
test and a simulated observer on a built study; and a pilot's human words from held-out
writers)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from prg.errors import UsageError
from prg.pipeline.word import WordTrajectory
from studies.cli import main
from studies.judge import judge, trajectory_features, word_centred
from tests.helpers.browser import human_dir, robot_dir
from tests.helpers.study_judge import REPO, WORDS, _build


def _zigzags(folder: Path) -> Path:
    """Robot words no person writes: the same sharp zigzag, whatever the word."""
    folder.mkdir(parents=True, exist_ok=True)
    for word in WORDS:
        x = np.linspace(0.0, 3.0, 61)
        pts = np.column_stack([x, 0.5 * (np.arange(61) % 2)])
        seg = np.minimum(np.arange(61) * len(word) // 61, len(word) - 1)
        WordTrajectory(pts, seg, ["letter"] * len(word), word).to_json(folder / f"{word}.json")
    return folder


def test_a_robot_that_writes_no_word_like_a_person_is_picked_out(tmp_path):
    humans = human_dir(tmp_path / "human", WORDS, 6)
    folder = _build(tmp_path / "study", _zigzags(tmp_path / "robot"), humans, writers=6)
    result = judge(folder, n_options=4, trials_per_word=50)
    assert result["c2st"]["trajectories"]["balanced_accuracy"] > 0.8
    assert result["observer"]["pick_rate"] > 0.8
    assert json.loads((folder / "judge.json").read_text())["observer"] == result["observer"]


def test_the_result_has_its_measures_intervals_and_chance(tmp_path):
    humans = human_dir(tmp_path / "human", WORDS, 5, seed=1)
    robot = robot_dir(tmp_path / "robot", WORDS, seed=7)  # written like the humans' words
    folder = _build(tmp_path / "study", robot, humans, writers=5)
    result = judge(folder, n_options=5, trials_per_word=40)
    assert result["chance"] == pytest.approx(0.2) and result["words"] == len(WORDS)
    for c in result["c2st"].values():
        assert 0 <= c["ci95"][0] <= c["ci95"][1] <= 1 and 0 <= c["balanced_accuracy"] <= 1
    obs = result["observer"]
    assert set(obs["by_word"]) == set(WORDS)
    assert obs["ci95"][0] <= obs["pick_rate"] <= obs["ci95"][1]


def test_features_ignore_where_and_how_big_a_word_is_and_words_are_centred():
    rng = np.random.default_rng(0)
    stroke = rng.normal(size=(40, 2)).cumsum(0)
    moved = trajectory_features((stroke * 3.0 + 5.0,))
    np.testing.assert_allclose(moved, trajectory_features((stroke,)), atol=1e-9)
    x = np.array([[1.0], [3.0], [10.0], [14.0]])
    np.testing.assert_array_equal(
        word_centred(x, np.array(["a", "a", "b", "b"])), [[-1.0], [1.0], [-2.0], [2.0]]
    )


def test_more_robot_words_are_written_as_the_studys_robot_writes(
    tmp_path, untrained_muse_checkpoint
):
    humans = human_dir(tmp_path / "human", WORDS, 4, seed=3)
    args = ["build", str(REPO / "conf/study/turing.yaml"), "--out", str(tmp_path / "s"), "-q"]
    args += ["--ckpt", str(untrained_muse_checkpoint), "--human", str(humans)]
    for s in (f"words=[{', '.join(WORDS)}]", "human_writers=4", "foils=3"):
        args += ["--set", s]
    assert main(args) == 0
    result = judge(tmp_path / "s", n_options=4, trials_per_word=20, robot_per_word=2)
    assert result["robot_samples"] == 3 * len(WORDS) and result["robot_per_word"] == 3
    given = _build(tmp_path / "given", robot_dir(tmp_path / "robot", WORDS), humans)
    with pytest.raises(UsageError, match="given as files"):
        judge(given, robot_per_word=1)
