"""Tests of ``prg.recording.simulation`` (moved from the suite on: the simulated robot writes:
accuracy, ink, lifts between words, workspace, IK, both arms, outputs, and the Rerun recording
read back from disk)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from prg.recording import read_entities
from prg.recording.simulation import recording_urdf
from tests.helpers.sim import _config, panda_hi, recording  # noqa: F401 (fixtures)


def test_the_urdf_for_rerun_has_visual_meshes_with_absolute_paths(tmp_path):
    robot, _ = _config()
    root = ET.parse(recording_urdf(robot, tmp_path)).getroot()
    assert not list(root.iter("collision"))
    meshes = [m.get("filename") for m in root.iter("mesh")]
    assert meshes and all(Path(m).is_absolute() and Path(m).is_file() for m in meshes)


def test_the_recording_holds_the_arm_pen_ink_and_command(recording, panda_hi):
    entities = read_entities(recording)
    joints = [f"world/panda/joints/{j}" for j in panda_hi.robot.arm_joints]
    assert set(joints) <= set(entities)
    assert {"Transform3D:child_frame", "Transform3D:quaternion"} <= entities[joints[0]]
    meshes = [e for e in entities if e.startswith("world/panda/visual_geometries/")]
    assert len(meshes) >= 8 and all("Asset3D:blob" in entities[e] for e in meshes)
    for entity in ("world/ink", "world/pen/tip", "world/pen/path", "world/commanded", "page/ink"):
        assert entity in entities
    assert "page_render" in entities and "summary" in entities
