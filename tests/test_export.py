"""A written word exported to real machines (prg.export, prg-export): every file is read back
with another reader (gcodeparser, an HPGL parser written here, vpype's SVG reader, mcap-ros2's
reader, numpy) and compared with what the word, its DMP timing and the simulated arm say
independently; the joint-limit check slows a too-fast timing by the smallest factor and refuses
what no slow-down fixes."""

from __future__ import annotations

import json
import logging
import math
import re
import warnings
from dataclasses import replace

import numpy as np
import pytest
from numpy.testing import assert_allclose

from prg.commands.cli import compose_config
from prg.errors import SettingsError, UsageError
from prg.export import (
    ExportSettings,
    GcodeSettings,
    HpglSettings,
    JointLimits,
    LimitSettings,
    PlotterSettings,
    export_word,
)
from prg.export.limits import check_timing, divided_differences
from prg.export.plotter import gcode_text, place_word, timed_strokes
from prg.export.robot import robot_trajectory
from prg.sim import SimSettings, font_word, simulate_word, word_samples
from tests.conftest import run_cli

DT = 0.01  # s, the G-code's sample spacing in these tests
A4 = (297.0, 210.0)
PANDA_ARM = slice(0, 7)  # panda.urdf's movable joints: panda_joint1..7, then the two fingers


# ----------------------------------------------------------------------------- fixtures


@pytest.fixture(scope="module")
def word():
    return font_word("h i")


@pytest.fixture(scope="module")
def panda_datasheet():
    """The Panda's datasheet limits as conf/export.yaml gives them."""
    from omegaconf import OmegaConf

    from prg.sim import RobotSettings

    node = OmegaConf.to_container(compose_config("export", []).limits.joints.panda)
    return JointLimits.from_mapping(RobotSettings.named("panda").arm_joints, node)


@pytest.fixture(scope="module")
def written(word):
    """The Panda writes "h i" at the DMP's own tempo."""
    return simulate_word(word, "panda", render=False)


@pytest.fixture(scope="module")
def rushed(word):
    """The Panda writes "h i" five times faster than the DMP's tempo."""
    return simulate_word(word, "panda", replace(SimSettings(), tempo=0.2), render=False)


# ----------------------------------------------------------------------------- expectations


def _ink_pieces(word) -> list[np.ndarray]:
    return [np.asarray(p) for _, p in word.polylines(highlight=False)]


def _centred(word, paper=A4, scale=1.0):
    """Word cm -> sheet mm for a word centred on the sheet (the default placement)."""
    ink = np.concatenate(_ink_pieces(word))
    middle = (ink.min(axis=0) + ink.max(axis=0)) / 2
    return lambda pts: np.asarray(paper) / 2 + 10.0 * scale * (np.asarray(pts) - middle)


def _timed(word, tempo=1.0):
    """The word's timed pen-down runs (sheet mm) and its pen-down time, from word_samples."""
    samples, t, down = word_samples(word, DT, tempo)
    place = _centred(word)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], down.astype(int), [0]])))
    runs = [place(samples[a:b]) for a, b in zip(edges[::2], edges[1::2])]
    both = down[1:] & down[:-1]
    return runs, float(np.diff(t)[both].sum())


def _nearest(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from each point of ``a`` to the nearest point of ``b``."""
    from scipy.spatial import cKDTree

    return cKDTree(b).query(a)[0]


def _length(polylines) -> float:
    return sum(float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()) for p in polylines)


# ----------------------------------------------------------------------------- readers


def parse_gcode(text: str, z_down: float = 0.0, servo_down: str = "M3", servo_up: str = "M5"):
    """Pen-down polylines (mm) and pen-down time (s) of a G-code program, read with gcodeparser:
    the pen is down after a Z move to ``z_down`` or a ``servo_down`` command; the time is the
    G1 moves' distance / feed and the G4 dwells while down, but the wait right after a servo
    command (the pen settling)."""
    from gcodeparser import parse_gcode_lines

    pos, feed, down, settling = np.zeros(2), None, False, False
    strokes, seconds = [], 0.0
    for line in parse_gcode_lines(text):
        cmd, params = line.command_str, line.params
        if cmd in (servo_down, servo_up):
            down = cmd == servo_down
            if down:
                strokes.append([pos.copy()])
            settling = True
            continue
        if cmd == "G4":
            if down and not settling:
                seconds += float(params["P"])
            settling = False
            continue
        settling = False
        if cmd not in ("G0", "G1"):
            continue
        feed = params.get("F", feed)
        if "Z" in params:
            now_down = params["Z"] <= z_down + 1e-9
            if now_down and not down:
                strokes.append([pos.copy()])
            down = now_down
        if "X" in params or "Y" in params:
            new = np.array([params.get("X", pos[0]), params.get("Y", pos[1])], dtype=float)
            if down:
                assert cmd == "G1", "a rapid move with the pen down"
                seconds += float(np.linalg.norm(new - pos)) / feed * 60.0
                strokes[-1].append(new)
            pos = new
    return [np.array(s) for s in strokes], seconds


def parse_hpgl(text: str, device: str = "hp7475a", page: str = "a4", paper=A4):
    """Pen-down polylines of HPGL (PU/PD/PA/PR, integer plotter units), in sheet mm (y up from
    the lower-left corner): the device's unit length and origin from vpype's profile, its y
    axis up."""
    import vpype as vp

    mm = vp.convert_length("mm")
    config = vp.config_manager.get_plotter_config(device)
    paper_config = config.paper_config(page)
    unit = config.plotter_unit_length / mm
    ox, oy = (v / mm for v in paper_config.origin_location)
    assert paper_config.y_axis_up and paper_config.origin_location_reference == "topleft"
    pos, down, relative, strokes = np.zeros(2), False, False, []
    for token in filter(None, (t.strip() for t in text.split(";"))):
        op, args = token[:2], token[2:]
        numbers = [int(v) for v in args.split(",")] if args else []
        if op == "PA":
            relative = False
        elif op == "PR":
            relative = True
        elif op in ("PU", "PD"):
            down = op == "PD"
            for x, y in zip(numbers[::2], numbers[1::2]):
                pos = pos + np.array([x, y]) if relative else np.array([x, y])
                if down:
                    strokes[-1].append(pos.copy())
                else:
                    strokes.append([pos.copy()])
    out = []
    for stroke in strokes:
        if len(stroke) < 2:
            continue
        pu = np.array(stroke, dtype=float)
        out.append(np.column_stack([ox + pu[:, 0] * unit, paper[1] - (oy - pu[:, 1] * unit)]))
    return out, unit


def read_mcap(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # the module's own import warning
        from mcap_ros2.reader import read_ros2_messages
    return {m.channel.topic: m for m in read_ros2_messages(str(path))}


# ----------------------------------------------------------------------------- G-code


def test_gcode_follows_the_timed_word_within_a_hundredth_of_a_millimetre_and_its_time(word):
    runs, pen_down_s = _timed(word)
    placement = place_word(word, PlotterSettings())
    program = gcode_text(timed_strokes(word, placement, DT), PlotterSettings(), GcodeSettings())
    strokes, seconds = parse_gcode(program.text)
    assert len(strokes) == len(runs) >= 2  # two words (and the i's dot)
    for parsed, expected in zip(strokes, runs):
        assert _nearest(parsed, expected).max() < 0.01
        assert _nearest(expected, parsed).max() < 0.01
        assert_allclose(parsed[[0, -1]], expected[[0, -1]], atol=0.001)
    assert seconds == pytest.approx(pen_down_s, rel=1e-3)
    assert program.pen_down_s == pytest.approx(seconds, rel=1e-6)
    header = program.text.splitlines()[:5]
    assert {"G21", "G90"} <= {line.split()[0] for line in header}


def test_gcode_in_inches_is_the_same_path_and_time(word):
    runs, pen_down_s = _timed(word)
    placement = place_word(word, PlotterSettings())
    settings = GcodeSettings(units="inch", decimals=5, z_up_mm=5.08)
    program = gcode_text(timed_strokes(word, placement, DT), PlotterSettings(), settings)
    strokes, seconds = parse_gcode(program.text)
    assert len(strokes) == len(runs)
    for parsed, expected in zip(strokes, runs):
        assert _nearest(parsed * 25.4, expected).max() < 0.01  # inches back to mm
    assert seconds == pytest.approx(pen_down_s, rel=1e-3)
    lines = program.text.splitlines()
    assert lines[1].startswith("G20") and "G0 Z0.20000" in lines
    with pytest.raises(SettingsError, match="units"):
        GcodeSettings(units="cm")


def test_gcode_at_half_the_tempo_takes_twice_as_long(word):
    placement = place_word(word, PlotterSettings())
    fast = gcode_text(timed_strokes(word, placement, DT, 1.0), PlotterSettings(), GcodeSettings())
    slow = gcode_text(timed_strokes(word, placement, DT, 2.0), PlotterSettings(), GcodeSettings())
    (fast_strokes, fast_s), (slow_strokes, slow_s) = parse_gcode(fast.text), parse_gcode(slow.text)
    assert len(slow_strokes) == len(fast_strokes)
    assert slow_s == pytest.approx(_timed(word, tempo=2.0)[1], rel=1e-3)
    # twice as long, but for where the pen-down runs end: each rollout's own samples decide it
    assert slow_s == pytest.approx(2 * fast_s, rel=1e-2)


def test_servo_pen_and_origin_offset_move_the_program_not_the_timing(word):
    runs, pen_down_s = _timed(word)
    placement = place_word(word, PlotterSettings())
    settings = GcodeSettings(
        pen="servo", servo_down="M3 S90", servo_up="M5", servo_wait_s=0.3, origin_mm=(100, -20)
    )
    program = gcode_text(timed_strokes(word, placement, DT), PlotterSettings(), settings)
    strokes, seconds = parse_gcode(program.text)
    assert len(strokes) == len(runs)
    for parsed, expected in zip(strokes, runs):
        assert _nearest(parsed, expected + np.array([100.0, -20.0])).max() < 0.01
    assert seconds == pytest.approx(pen_down_s, rel=1e-3)
    lines = program.text.splitlines()
    assert not [line for line in lines if re.match(r"G[01] .*Z", line)]  # no Z moves
    assert lines.count("M3 S90") == len(runs) and lines.count("G4 P0.300") == 2 * len(runs) + 1


def test_a_word_off_the_sheet_or_too_fast_or_without_a_dmp_is_refused(word):
    placement = place_word(word, PlotterSettings(scale=30.0))
    with pytest.raises(UsageError, match=r"does not fit the 297 x 210 mm paper"):
        gcode_text(timed_strokes(word, placement, DT), PlotterSettings(scale=30.0), GcodeSettings())
    moved = PlotterSettings(position_mm=(290.0, 10.0))
    with pytest.raises(UsageError, match=r"does not fit .*move it \(plotter\.position_mm\)"):
        export_word(word, ExportSettings(formats=("svg",), plotter=moved))
    with pytest.raises(UsageError, match=r"needs a feed of \d+ mm/min, more than gcode\.max_feed"):
        export_word(
            word, ExportSettings(formats=("gcode",), gcode=GcodeSettings(max_feed_mm_min=500))
        )
    undated = replace(word, dmp=None)
    with pytest.raises(UsageError, match=r"has no DMP: gcode follow"):
        export_word(undated, ExportSettings(formats=("svg", "gcode")))
    assert export_word(undated, ExportSettings(formats=("svg", "hpgl"))).metadata["plotter"]
    with pytest.raises(UsageError, match=r"unknown format 'pdf'"):
        ExportSettings(formats=("svg", "pdf"))


# ----------------------------------------------------------------------------- HPGL and SVG


def test_hpgl_reads_back_to_the_ink_within_the_plotters_resolution(word, tmp_path):
    result = export_word(word, ExportSettings(formats=("hpgl",)), tmp_path)
    strokes, unit = parse_hpgl(result.files["hpgl"].read_text())
    place = _centred(word)
    ink = [place(p) for p in _ink_pieces(word)]
    resolution = unit * math.sqrt(2) / 2 + 1e-9  # half a plotter unit, both axes
    assert _nearest(np.concatenate(strokes), np.concatenate(ink)).max() <= resolution
    assert _nearest(np.concatenate(ink), np.concatenate(strokes)).max() <= resolution
    n_points = sum(len(s) for s in strokes)
    assert _length(strokes) == pytest.approx(_length(ink), abs=n_points * unit)  # no travel inked


def test_hpgl_refuses_a_word_on_the_sheet_but_out_of_the_plotters_reach(word):
    # the hp7475a's a4 area starts 10 mm from the sheet's left edge (vpype's profile)
    near_edge = PlotterSettings(position_mm=(3.0, 100.0))
    export_word(word, ExportSettings(formats=("svg",), plotter=near_edge))  # on the sheet
    with pytest.raises(UsageError, match=r"does not fit the area the hp7475a reaches on a4"):
        export_word(word, ExportSettings(formats=("hpgl",), plotter=near_edge))
    with pytest.raises(UsageError, match=r"has no paper of 300 x 200 mm"):
        export_word(word, ExportSettings(formats=("hpgl",), plotter=PlotterSettings((300, 200))))
    a3 = PlotterSettings(paper_mm=(420.0, 297.0))
    text = export_word(word, ExportSettings(formats=("hpgl",), plotter=a3)).metadata
    assert text["plotter"]["hpgl_device"] == "hp7475a"
    with pytest.raises(UsageError, match=r"not a plotter vpype knows"):
        export_word(word, ExportSettings(formats=("hpgl",), hpgl=HpglSettings(device="nope")))


def test_plotter_svg_is_true_size_pen_down_only_and_reads_back_with_vpype(word, tmp_path):
    import xml.etree.ElementTree as ET

    import vpype as vp

    path = export_word(word, ExportSettings(formats=("svg",)), tmp_path).files["svg"]
    root = ET.parse(path).getroot()
    assert (root.get("width"), root.get("height")) == ("29.7cm", "21.0cm")
    tags = {el.tag.split("}")[-1] for el in root.iter()}
    assert "rect" not in tags and "polyline" in tags  # no background
    lines, width, height = vp.read_svg(str(path), quantization=0.01)
    mm = vp.convert_length("mm")
    assert_allclose([width / mm, height / mm], A4, atol=0.01)
    read = [np.column_stack([line.real / mm, A4[1] - line.imag / mm]) for line in lines]
    place = _centred(word)
    ink = [place(p) for p in _ink_pieces(word)]
    assert _nearest(np.concatenate(read), np.concatenate(ink)).max() < 1e-3
    assert _nearest(np.concatenate(ink), np.concatenate(read)).max() < 1e-3
    assert _length(read) == pytest.approx(_length(ink), rel=1e-5)  # no pen-up travel drawn


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


# ----------------------------------------------------------------------------- limits


def test_divided_differences_of_a_known_motion_on_an_uneven_grid():
    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0.004, 0.006, 400))
    q = np.column_stack([np.sin(t), 0.5 * t**3])
    d = divided_differences(t, q)
    v, tv = d["velocity"]
    a, ta = d["acceleration"]
    j, _ = d["jerk"]
    assert v.shape == (399, 2) and a.shape == (398, 2) and j.shape == (397, 2)
    assert_allclose(v[:, 0], np.cos(tv), atol=1e-4)
    # on a cubic, the acceleration over three samples is exact at their mean time and the jerk
    # is exact (3) everywhere, however uneven the spacing
    assert_allclose(ta, (t[:-2] + t[1:-1] + t[2:]) / 3)
    assert_allclose(a[:, 1], 3 * ta, rtol=1e-6)
    assert_allclose(j[:, 1], 3.0, rtol=1e-4)


def test_a_too_fast_timing_is_slowed_by_the_smallest_factor_that_fits(
    rushed, panda_datasheet, caplog
):
    with caplog.at_level(logging.WARNING, logger="prg.export.robot"):
        trajectory = robot_trajectory(rushed, panda_datasheet)
    k = trajectory.slow_down
    assert k > 1.2
    assert "slowed" in caplog.text and f"{k:.4g}x" in caplog.text
    assert_allclose(trajectory.t, rushed.plan.t * k)
    limits = trajectory.limits
    sent = check_timing(trajectory.t, trajectory.q, limits)
    assert sent.slow_down == pytest.approx(1.0, abs=1e-9)
    limiting = trajectory.timing.limiting
    power = {"velocity": 1, "acceleration": 2, "jerk": 3}[limiting]
    assert sent.ratios[limiting] == pytest.approx(1.0, rel=1e-9)  # at the limit, not beyond
    assert check_timing(trajectory.t / 1.001, trajectory.q, limits).slow_down > 1.0
    assert trajectory.timing.ratios[limiting] == pytest.approx(k**power, rel=1e-9)


def test_the_slow_down_grows_in_proportion_to_the_speed_up(written, panda_datasheet):
    q = written.q_plan[:, PANDA_ARM]
    k5 = check_timing(written.plan.t / 5, q, panda_datasheet).slow_down
    k10 = check_timing(written.plan.t / 10, q, panda_datasheet).slow_down
    assert k5 > 1 and k10 == pytest.approx(2 * k5, rel=1e-9)


def test_no_timing_fits_beyond_the_slow_down_allowed_or_outside_the_joint_range(
    rushed, written, panda_datasheet
):
    with pytest.raises(
        UsageError, match=r"must be slowed [\d.]+x, more than limits\.max_slow_down=1\.1"
    ):
        robot_trajectory(rushed, panda_datasheet, LimitSettings(max_slow_down=1.1))
    q = written.q_plan[:, PANDA_ARM]
    upper = panda_datasheet.upper.copy()
    upper[3] = q[:, 3].max() - 0.01  # joint 4 ends 0.01 rad short of where the word takes it
    cramped = replace(panda_datasheet, upper=upper)
    with pytest.raises(UsageError, match=r"^panda_joint4 reaches -?[\d.]+ rad at t = .* outside"):
        check_timing(written.plan.t * 100, q, cramped)  # however slow


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


# ----------------------------------------------------------------------------- the command


def test_the_simulation_settings_of_prg_export_are_prg_simulates():
    export, simulate = compose_config("export", []), compose_config("simulate", [])
    for key in ("paper", "motion", "control", "ik", "workspace_step_cm", "scale", "tempo"):
        assert export[key] == simulate[key], key
    assert export.robot == simulate.robot


def test_prg_export_writes_every_format_and_refuses_bad_input_writing_nothing(word, tmp_path):
    source = word.to_json(tmp_path / "hi.json")
    out = tmp_path / "out"
    common = [f"paths.root_dir={tmp_path}", f"out_dir={out}"]
    done = run_cli("prg-export", f"word={source}", *common)
    assert done.returncode == 0, done.stderr
    names = {p.name for p in out.iterdir()}
    assert names == {"word.gcode", "word.hpgl", "word.svg", "word.mcap", "word.csv", "export.json"}
    meta = json.loads((out / "export.json").read_text())
    assert meta["text"] == "h i" and meta["robot"]["timing"]["slow_down"] == 1.0
    _, seconds = parse_gcode((out / "word.gcode").read_text())
    assert seconds == pytest.approx(_timed(word)[1], rel=1e-3)
    assert len(read_mcap(out / "word.mcap")["/joint_trajectory"].ros_msg.points) == len(
        np.loadtxt(out / "word.csv", delimiter=",", skiprows=1)
    )
    fresh = tmp_path / "fresh"
    missing = run_cli(
        "prg-export", f"word={tmp_path / 'nope.json'}", *common[:1], f"out_dir={fresh}"
    )
    assert missing.returncode == 2
    assert re.fullmatch(
        r"prg-export: error: .*nope\.json: no such word trajectory file\n", missing.stderr
    )
    too_big = run_cli("prg-export", f"word={source}", "scale=30", *common[:1], f"out_dir={fresh}")
    assert too_big.returncode == 2 and too_big.stderr.count("\n") == 1
    assert "does not fit" in too_big.stderr
    assert not fresh.exists()


def test_prg_export_puts_each_word_in_a_new_folder_by_default(word, tmp_path):
    source = word.to_json(tmp_path / "hi.json")
    runs = [
        run_cli("prg-export", f"word={source}", f"paths.root_dir={tmp_path}", "formats=[svg]")
        for _ in range(2)
    ]
    assert all(r.returncode == 0 for r in runs), runs[-1].stderr
    folders = sorted((tmp_path / "outputs/export").iterdir())
    assert len(folders) == 2  # the second run did not overwrite the first
    for folder in folders:
        assert re.fullmatch(r"h_i-\d{8}-\d{6}(-2)?", folder.name), folder.name
        assert {p.name for p in folder.iterdir()} == {"word.svg", "export.json"}
