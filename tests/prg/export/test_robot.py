"""Tests of ``prg.export.robot`` (moved from the suite on: a written word exported to real machines
(prg.export, prg-export): every file is read back with another reader (gcodeparser, an HPGL
parser written here, vpype's SVG reader, mcap-ros2's reader, numpy) and compared with what the
word, its DMP timing and the simulated arm say independently; the joint-limit check slows a too-
fast timing by the smallest factor and refuses what no slow-down fixes)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from numpy.testing import assert_allclose

from prg.errors import UsageError
from prg.export import (
    LimitSettings,
)
from prg.export.robot import robot_trajectory
from tests.helpers.export import (  # noqa: F401 (fixtures)
    PANDA_ARM,
    panda_datasheet,
    read_mcap,
    word,
    written,
)

# ----------------------------------------------------------------------------- robot files


def test_mcap_holds_the_commanded_joints_and_the_pen_path_in_the_base_frame(
    written, panda_datasheet, tmp_path
):
    from prg.export.robot import write_mcap

    trajectory = robot_trajectory(written, panda_datasheet)
    assert trajectory.slow_down == 1.0
    messages = read_mcap(write_mcap(trajectory, tmp_path / "word.mcap"))
    assert set(messages) == {"/joint_trajectory", "/pen_path"}
    joints = messages["/joint_trajectory"].ros_msg
    assert messages["/joint_trajectory"].schema.name == "trajectory_msgs/msg/JointTrajectory"
    assert joints.header.frame_id == "panda_link0"
    assert list(joints.joint_names) == [f"panda_joint{i}" for i in range(1, 8)]
    plan = written.plan
    t = [p.time_from_start.sec + p.time_from_start.nanosec * 1e-9 for p in joints.points]
    assert_allclose(t, plan.t, atol=1e-9)
    assert_allclose([p.positions for p in joints.points], written.q_plan[:, PANDA_ARM])
    path = messages["/pen_path"].ros_msg
    assert messages["/pen_path"].schema.name == "nav_msgs/msg/Path"
    assert {p.header.frame_id for p in path.poses} == {"panda_link0"}
    xyz = np.array([[p.pose.position.x, p.pose.position.y, p.pose.position.z] for p in path.poses])
    # the commanded tip, paper frame (cm) -> world (m) -> the base frame (the base stands at
    # robot.base_position, not turned)
    commanded = written.settings.paper.to_world(plan.tip) - np.asarray(written.robot.base_position)
    assert np.abs(xyz - commanded).max() <= written.ik_error_m.max() + 1e-9
    quat = np.array([[getattr(p.pose.orientation, k) for k in "xyzw"] for p in path.poses])
    pen = _rotate(quat, np.asarray(written.robot.pen_offset))
    assert_allclose(
        pen / np.linalg.norm(pen, axis=1, keepdims=True), [[0, 0, -1]] * len(pen), atol=1e-4
    )
    assert np.all(np.einsum("ij,ij->i", quat[1:], quat[:-1]) > 0)  # no sign jumps


def _rotate(quaternions: np.ndarray, vector: np.ndarray) -> np.ndarray:
    """Each quaternion (x, y, z, w) applied to ``vector``, via its rotation matrix."""
    x, y, z, w = quaternions.T
    rot = np.stack(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    ).transpose(2, 0, 1)
    return rot @ vector


def test_csv_rows_are_the_waypoints_with_time_joints_pose_and_pen(
    written, panda_datasheet, tmp_path
):
    from prg.export.robot import write_csv

    trajectory = robot_trajectory(written, panda_datasheet)
    path = write_csv(trajectory, tmp_path / "word.csv")
    header = path.read_text().splitlines()[0].split(",")
    assert header == [
        "t_s",
        *trajectory.joint_names,
        "x_m",
        "y_m",
        "z_m",
        "qx",
        "qy",
        "qz",
        "qw",
        "pen_down",
    ]
    table = np.loadtxt(path, delimiter=",", skiprows=1)
    assert_allclose(table[:, 0], written.plan.t, atol=1e-9)
    assert_allclose(table[:, 1:8], written.q_plan[:, PANDA_ARM], atol=1e-9)
    assert_allclose(table[:, 8:11], trajectory.tip_position, atol=1e-9)
    assert_allclose(np.linalg.norm(table[:, 11:15], axis=1), 1.0, atol=1e-8)
    assert_allclose(table[:, 15], written.plan.pen_down)
    # pen-down rows are on the paper: its surface is 0.5 mm above the base (0.6255 - 0.625 m)
    paper_z = written.settings.paper.centre[2] - written.robot.base_position[2]
    assert_allclose(table[table[:, 15] == 1, 10], paper_z, atol=1e-6)


def test_the_pen_must_touch_the_paper_and_not_press_beyond_its_give(written, panda_datasheet):
    paper = written.settings.paper
    x, y, z = paper.centre
    ok = robot_trajectory(written, panda_datasheet)
    assert abs(ok.contact.above_mm) < 0.01
    raised = replace(paper, centre=(x, y, z + 0.001))  # the real paper 1 mm higher
    with pytest.raises(UsageError, match=r"presses 1\.0\d\d mm into the paper .* than the 0\.5 mm"):
        robot_trajectory(written, panda_datasheet, paper=raised)
    lowered = replace(paper, centre=(x, y, z - 0.001))
    with pytest.raises(UsageError, match=r"pen is 1\.0\d\d mm above the paper .* should write"):
        robot_trajectory(written, panda_datasheet, paper=lowered)
    lenient = LimitSettings(contact_above_mm=1.5)
    assert robot_trajectory(written, panda_datasheet, lenient, lowered).contact.above_mm > 0.99
