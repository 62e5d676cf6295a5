"""Tests of ``prg.recording.read`` (moved from the suite on: rerun recordings: a written word with
its inputs and animated DMP rollout, read back from disk)."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from prg.errors import UsageError
from prg.recording import (
    read_component,
    read_entities,
    read_times,
    recording_summary,
)
from prg.sim.geometry import pen_down_samples
from tests.helpers.recording import FLIP, FLOAT32, NANOSECOND, written  # noqa: F401 (fixtures)
from tests.helpers.sim import panda_hi, recording  # noqa: F401 (fixtures)


def test_the_rollout_is_animated_on_the_word_time_grid(written):
    path, rollout = written["path"], written["rollout"]
    n = len(rollout)
    summary = recording_summary(path)
    assert summary["word/rollout/pen"]["time"] == n
    # one ink segment per step whose both ends are pen-down (none across the space's travel)
    word = written["word"]
    body = slice(0, word.body_end)
    down = pen_down_samples(word.points[body], word.segment[body], word.segment_kinds, rollout)
    assert not down.all()  # "ab cd": some samples travel over the space, pen up
    assert summary["word/rollout/path"]["time"] == int((down[1:] & down[:-1]).sum())
    times = read_times(path, "word/rollout/pen", "time")
    grid = np.linspace(0, written["word"].duration_s, n)
    np.testing.assert_allclose(times, grid, atol=NANOSECOND)
    rows = read_component(path, "word/rollout/pen", "Points2D:positions", "time")
    pen = np.array([row[0] for row in rows])
    np.testing.assert_allclose(pen, rollout * FLIP, atol=FLOAT32)
    segments = read_component(path, "word/rollout/path", "LineStrips2D:strips", "time")
    np.testing.assert_allclose(segments[-1][0], rollout[-2:] * FLIP, atol=FLOAT32)


def test_reading_a_missing_or_foreign_file_names_it(tmp_path):
    with pytest.raises(UsageError, match="no such recording file"):
        read_entities(tmp_path / "none.rrd")
    junk = tmp_path / "junk.rrd"
    junk.write_bytes(b"not a recording")
    with pytest.raises(UsageError, match=r"junk\.rrd: not a readable Rerun recording"):
        read_entities(junk)


def test_the_recorded_joint_transforms_put_the_pen_tip_where_the_simulation_had_it(
    recording, panda_hi
):
    """Chain the recorded transforms (base, animated joints, fixed joints) at one frame and
    compare the pen tip with PyBullet's."""
    from scipy.spatial.transform import Rotation

    r = panda_hi
    parents = dict(
        zip(
            [
                c[0]
                for c in read_component(
                    recording, "world/panda/tf_static", "Transform3D:child_frame"
                )
            ],
            zip(
                read_component(recording, "world/panda/tf_static", "Transform3D:parent_frame"),
                read_component(recording, "world/panda/tf_static", "Transform3D:translation"),
                read_component(recording, "world/panda/tf_static", "Transform3D:quaternion"),
            ),
        )
    )
    frames = read_times(recording, "world/pen/tip", "sim_time")
    k = len(frames) // 2
    step = int(np.argmin(np.abs(r.t - frames[k])))
    for name in r.robot.arm_joints:
        entity = f"world/panda/joints/{name}"
        child = read_component(recording, entity, "Transform3D:child_frame", "sim_time")[k][0]
        parent = read_component(recording, entity, "Transform3D:parent_frame", "sim_time")[k][0]
        translation = read_component(recording, entity, "Transform3D:translation", "sim_time")[k]
        quaternion = read_component(recording, entity, "Transform3D:quaternion", "sim_time")[k]
        parents[child] = ([parent], translation, quaternion)
    base = "world/panda/base"
    parents["panda_link0"] = (
        read_component(recording, base, "Transform3D:parent_frame")[0],
        read_component(recording, base, "Transform3D:translation")[0],
        read_component(recording, base, "Transform3D:quaternion")[0],
    )
    frame, pose_t, pose_r = r.robot.flange_link, np.zeros(3), Rotation.identity()
    while frame in parents:
        parent, translation, quaternion = parents[frame]
        rotation = Rotation.from_quat(np.asarray(quaternion, dtype=float).reshape(4))
        pose_t = rotation.apply(pose_t) + np.asarray(translation, dtype=float).reshape(3)
        pose_r = rotation * pose_r
        frame = parent[0]
    assert frame == "tf#/world"
    tip = pose_t + pose_r.apply(r.robot.pen_offset)
    assert_allclose(tip, r.tip_world[step], atol=1e-4)
