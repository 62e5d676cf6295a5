"""Tests of ``prg.sim.robots`` (moved from the suite on: the simulated robot writes: accuracy, ink,
lifts between words, workspace, IK, both arms, outputs, and the Rerun recording read back from
disk)."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from prg.errors import SettingsError, UsageError
from prg.sim import (
    IKSolver,
    RobotSettings,
    Scene,
    font_word,
    simulate_word,
)
from tests.helpers.sim import _config, panda_hi  # noqa: F401 (fixtures)
from tests.helpers.sim_settings import CONF, _yaml

FLOAT32_M = 2e-6  # positions in the recording are float32 metres


def test_a_short_word_is_written_within_half_a_millimetre_without_ink_gaps(panda_hi):
    m = panda_hi.metrics
    assert m["tracking_error_mean_mm"] < 0.5
    assert m["tracking_error_max_mm"] < 0.5
    assert 0 < m["max_ink_gap_mm"] <= m["pen_step_mm"]
    assert m["ink_strokes"] == m["commanded_strokes"] == 2  # the word, then the i's dot
    assert m["sim_s"] > m["writing_s"] > 0


def test_the_pen_inks_only_between_lowering_and_lifting(panda_hi):
    r = panda_hi
    heights = r.tip_paper[:, 2]
    assert not r.contact[0] and not r.contact[-1]
    assert heights[0] > 10 and heights[-1] > 10  # starts and ends home, well above the paper
    assert set(r.step_stroke[r.contact]) == {0, 1}  # all ink belongs to the commanded strokes
    assert np.all(np.abs(heights[r.contact]) <= 0.05)


def test_the_iiwa_loads_and_writes_a_letter():
    robot, settings = _config("iiwa")
    assert robot.name == "iiwa"
    result = simulate_word(font_word("c"), robot, settings, render=False)
    assert result.metrics["tracking_error_mean_mm"] < 0.5
    assert result.metrics["max_ink_gap_mm"] <= result.metrics["pen_step_mm"]


@pytest.mark.parametrize("name", ["panda", "iiwa"])
def test_both_robots_load_with_seven_arm_joints_and_reach_the_paper_pen_down(name):
    robot, settings = _config(name)
    with Scene(robot, settings.paper) as scene:
        assert len(scene.robot.arm) == 7
        assert scene.robot.config.flange_link == robot.flange_link
        home = scene.tip_pose()[0]
        assert settings.paper.to_paper(home)[0, 2] > 10  # rest pose: pen well above the paper
    with IKSolver(robot) as ik:
        target = settings.paper.to_world([[3.0, 2.0, 0.0]])[0]
        q, error = ik.solve(target)
        assert error < 1e-5
        assert np.all(q >= ik.robot.lower - 1e-9) and np.all(q <= ik.robot.upper + 1e-9)


def test_a_word_off_the_paper_is_refused_before_anything_moves():
    robot, settings = _config(scale=30.0, workspace_step_cm=4.0)
    with pytest.raises(UsageError, match=r"off the paper; at most [\d.]+ cm wide .* set scale="):
        simulate_word(font_word("joy"), robot, settings)


def test_the_page_render_shows_the_ink(panda_hi):
    page = panda_hi.page
    assert page.shape == (768, 1024, 3) and page.dtype == np.uint8
    dark = page.min(axis=2) < 80
    assert dark.sum() > 200  # the ink
    rows, cols = np.nonzero(dark)
    assert abs(cols.mean() - 512) < 100 and abs(rows.mean() - 384) < 100  # framed in the centre


@pytest.mark.parametrize("path", sorted((CONF / "robot").glob("*.yaml")), ids=lambda p: p.stem)
def test_a_named_robot_is_its_conf_robot_yaml(path):
    robot = RobotSettings.named(path.stem)
    assert robot == RobotSettings.from_dict(_yaml(path))
    assert robot.name == path.stem and len(robot.arm_joints) == len(robot.rest_pose) == 7


def test_an_unknown_robot_lists_the_known_ones():
    with pytest.raises(
        SettingsError, match=r"^robot 'kuka' is not a known robot: choose iiwa, panda"
    ):
        RobotSettings.named("kuka")
    with pytest.raises(SettingsError, match="is not a known robot"):
        RobotSettings.named("../simulate")


def test_a_named_robot_reads_prg_conf_dir(tmp_path, monkeypatch):
    (tmp_path / "robot").mkdir()
    node = _yaml(CONF / "robot" / "panda.yaml") | {"name": "mine", "pen_length": 0.2}
    (tmp_path / "robot" / "mine.yaml").write_text(yaml.safe_dump(node))
    monkeypatch.setenv("PRG_CONF_DIR", str(tmp_path))
    assert RobotSettings.named("mine").pen_length == 0.2
    (tmp_path / "robot" / "bad.yaml").write_text(yaml.safe_dump(node | {"pen_offset": [0, 0]}))
    with pytest.raises(UsageError, match=r"bad\.yaml: pen_offset must be a list of 3 numbers"):
        RobotSettings.named("bad")


def test_robot_settings_name_the_field():
    node = _yaml(CONF / "robot" / "panda.yaml")
    with pytest.raises(SettingsError, match=r"^rest_pose must be 7 numbers \(rad\)") as err:
        RobotSettings.from_dict(node | {"rest_pose": [0.0, 1.0]})
    assert str(err.value.under("robot")).startswith("robot.rest_pose must be 7 numbers")
    with pytest.raises(SettingsError, match=r"^urdf is missing"):
        RobotSettings.from_dict({k: v for k, v in node.items() if k != "urdf"})
    with pytest.raises(SettingsError, match=r"^pen_offset must not be zero"):
        RobotSettings.from_dict(node | {"pen_offset": [0, 0, 0]})
