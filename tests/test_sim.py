"""The simulated robot writes: accuracy, ink, lifts between words, workspace, IK, both arms,
outputs, and the Rerun recording read back from disk."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from prg.errors import UsageError
from prg.recording import read_component, read_entities, read_times
from prg.recording.simulation import record_simulation, recording_urdf
from prg.sim import (
    IKSolver,
    Paper,
    ReachMap,
    RobotSettings,
    Scene,
    SimSettings,
    UnreachableError,
    check_workspace,
    font_word,
    ink_png,
    ink_svg,
    simulate_word,
)
from prg.sim.geometry import bounding_box, runs

FLOAT32_M = 2e-6  # positions in the recording are float32 metres


def _config(robot: str = "panda", **changes):
    """A robot of conf/robot/ and the settings of conf/simulate.yaml (the library defaults),
    with ``changes``."""
    return RobotSettings.named(robot), replace(SimSettings(), **changes)


@pytest.fixture(scope="module")
def panda_hi():
    """'hi' written by the Panda with the default settings of conf/simulate.yaml: the word in one
    stroke, then the i's dot."""
    robot, settings = _config()
    return simulate_word(font_word("hi"), robot, settings)


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


def test_the_ink_lands_where_the_word_was_placed(panda_hi):
    r = panda_hi
    low, high = bounding_box(np.concatenate(r.ink_strokes()))
    assert_allclose((low + high) / 2, r.placement["centre_cm"], atol=0.01)
    assert_allclose(high - low, [r.placement["width_cm"], r.placement["height_cm"]], atol=0.01)


def test_the_dot_is_inked_above_the_stem_after_a_pen_lift(panda_hi):
    r = panda_hi
    word_ink, dot_ink = r.ink_strokes()
    # on the paper the word is placed centred and scaled: map the word's own dot there
    word = font_word("hi")
    (dot,) = [word.segment_points(k) for k, kind in enumerate(word.segment_kinds) if kind == "mark"]
    low, high = bounding_box(word.points)
    scale, centre = r.placement["scale"], np.asarray(r.placement["centre_cm"])
    expected = (dot - (low + high) / 2) * scale + centre
    assert_allclose(dot_ink.mean(axis=0), expected.mean(axis=0), atol=0.02)
    assert dot_ink[:, 1].min() > word_ink[:, 1].max() - 0.5 * (high - low)[1]  # above the stem
    # between the two strokes the pen is in the air
    first_end = np.flatnonzero(r.step_stroke == 0)[-1]
    second_start = np.flatnonzero(r.step_stroke == 1)[0]
    assert r.tip_paper[first_end + 1 : second_start, 2].max() > 1.0


def test_two_words_are_two_strokes_with_the_pen_lifted_in_between():
    result = simulate_word(font_word("l l"), "panda", render=False)  # conf/simulate.yaml's settings
    m = result.metrics
    assert m["commanded_strokes"] == m["ink_strokes"] == 2
    assert m["ink_to_command_max_mm"] < 0.5  # no ink on the travel between the words
    travel = result.commanded[:, 2] > 1.0
    assert not np.any(result.contact & travel)
    first, second = result.ink_strokes()
    assert second[:, 0].min() - first[:, 0].max() > 0.5  # the space between the words


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


def test_null_space_ik_alone_misses_by_millimetres_and_the_refinement_fixes_it():
    robot, settings = _config()
    target = settings.paper.to_world([[5.0, 5.0, 0.0]])[0]
    with IKSolver(robot, settings.ik) as ik:
        refined = ik.solve(target)[1]
    from dataclasses import replace

    with IKSolver(robot, replace(settings.ik, method="null_space")) as ik:
        plain = ik.solve(target)[1]
    assert refined < 1e-6 < 1e-4 < plain


def test_an_unreachable_target_is_named():
    robot, _ = _config()
    with IKSolver(robot) as ik, pytest.raises(UnreachableError, match=r"\(2\.0000, 0\.0000"):
        ik.solve_path(np.array([[0.5, 0.0, 0.9], [2.0, 0.0, 0.9]]))


def test_a_word_too_large_for_the_workspace_is_refused_with_the_scale_that_fits():
    robot, settings = _config(paper=Paper(size_cm=(150.0, 100.0)))
    word = font_word("joy")
    low, high = bounding_box(word.points)
    anchor = (low + high) / 2
    with IKSolver(robot) as ik:
        reach = ReachMap(ik, settings.paper, (0.0, 1.5), step_cm=4.0)
        with pytest.raises(UsageError, match=r"out of reach; at most [\d.]+ cm wide") as err:
            check_workspace(word.points, anchor, np.zeros(2), 40.0, reach, "panda", "joy")
        fits = float(str(err.value).split("scale=")[-1].split()[0])
        assert 1.0 < fits < 40.0
        check_workspace(word.points, anchor, np.zeros(2), fits, reach, "panda", "joy")
        with pytest.raises(UsageError):
            check_workspace(word.points, anchor, np.zeros(2), fits * 1.05, reach, "panda", "joy")


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


def test_ink_png_and_svg_are_true_to_scale(tmp_path, panda_hi):
    strokes = panda_hi.ink_strokes()
    svg = ink_svg(strokes, tmp_path / "ink.svg").read_text()
    root = ET.fromstring(svg)
    polylines = root.findall("{http://www.w3.org/2000/svg}polyline")
    assert len(polylines) == len(strokes)
    low, high = bounding_box(np.concatenate(strokes))
    assert float(root.get("width").removesuffix("cm")) == pytest.approx(
        high[0] - low[0] + 0.6, abs=1e-3
    )
    from PIL import Image

    with Image.open(ink_png(strokes, tmp_path / "ink.png", dpi=300)) as image:
        assert image.size[0] == pytest.approx((high[0] - low[0] + 0.6) / 2.54 * 300, abs=2)
        assert (np.asarray(image.convert("L")) < 100).any()


def test_the_urdf_for_rerun_has_visual_meshes_with_absolute_paths(tmp_path):
    robot, _ = _config()
    root = ET.parse(recording_urdf(robot, tmp_path)).getroot()
    assert not list(root.iter("collision"))
    meshes = [m.get("filename") for m in root.iter("mesh")]
    assert meshes and all(Path(m).is_absolute() and Path(m).is_file() for m in meshes)


@pytest.fixture(scope="module")
def recording(panda_hi, tmp_path_factory) -> Path:
    return record_simulation(tmp_path_factory.mktemp("rrd") / "sim.rrd", panda_hi)


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


def test_ink_is_logged_once_per_inked_step_not_as_a_whole_line_per_frame(recording, panda_hi):
    r = panda_hi
    inked_steps = sum(b - a - 1 for a, b in runs(r.contact))
    times = read_times(recording, "world/ink", "sim_time")
    assert len(times) == inked_steps
    rows = read_component(recording, "page/ink", "LineStrips2D:strips", timeline="sim_time")
    assert all(len(row) == 1 and len(row[0]) == 2 for row in rows)  # one segment per row
    first = np.asarray(rows[0][0])
    a = runs(r.contact)[0][0]
    assert_allclose(first, r.tip_paper[a : a + 2, :2] * [1, -1], atol=1e-4)


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
