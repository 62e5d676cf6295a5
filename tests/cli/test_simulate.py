"""`prg-simulate`: word.json or text -> ink, page render, joints, metrics, sim.rrd, MLflow run;
bad input gets one line, exit code 2, and nothing is written."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
import rerun.blueprint as rrb
from mlflow import MlflowClient

from prg.recording import read_component, read_entities, read_times, read_views
from prg.sim import font_word
from prg.tracking import sqlite_uri
from tests.conftest import BIN, run_cli

OUTPUTS = {
    "ink.png",
    "ink.svg",
    "page.png",
    "joints.csv",
    "joints.npz",
    "metrics.json",
    "sim.rrd",
    "word",
}


def simulate_cli(*args: str, env: dict | None = None):
    """``prg-simulate ARGS`` (``python -m prg.commands.simulate`` until the console script is installed)."""
    if (BIN / "prg-simulate").exists():
        return run_cli("prg-simulate", "progress=false", *args, env=env)
    return run_cli("python", "-m", "prg.commands.simulate", "progress=false", *args, env=env)


@pytest.fixture(scope="module")
def word_json(tmp_path_factory) -> Path:
    return font_word("ok").to_json(tmp_path_factory.mktemp("word") / "word.json")


@pytest.fixture(scope="module")
def iiwa_run(tmp_path_factory, word_json) -> Path:
    """``prg-simulate word=ok.json robot=iiwa`` into its default folder; the root it ran in."""
    root = tmp_path_factory.mktemp("iiwa")
    result = simulate_cli(f"word={word_json}", f"paths.root_dir={root}", "robot=iiwa")
    assert result.returncode == 0, result.stderr[-2000:]
    return root


def _iiwa_folder(root: Path) -> Path:
    (folder,) = (root / "outputs" / "simulate" / "iiwa").iterdir()
    return folder


def test_simulates_a_word_json_into_every_output_and_an_mlflow_run(iiwa_run, word_json):
    out = _iiwa_folder(iiwa_run)
    assert re.fullmatch(r"ok-\d{8}-\d{6}", out.name), out.name  # <text>-<YYYYmmdd-HHMMSS>
    assert {p.name for p in out.iterdir()} == OUTPUTS
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["robot"] == "iiwa" and metrics["text"] == "ok"
    assert metrics["tracking_error_mean_mm"] < 0.5
    assert metrics["max_ink_gap_mm"] <= metrics["pen_step_mm"]
    assert metrics["sim_s"] > 0 and metrics["realtime_factor"] > 0
    assert (out / "word" / "word.json").read_bytes() == word_json.read_bytes()
    data = np.load(out / "joints.npz")
    assert data["q"].shape == (metrics["physics_steps"], 7)
    assert int(data["contact"].sum()) == metrics["ink_points"]
    header = (out / "joints.csv").read_text().splitlines()[0].split(",")
    assert header[0] == "t_s" and header[1] == "lbr_iiwa_joint_1" and header[-1] == "ink"
    assert "world/lbr_iiwa/joints/lbr_iiwa_joint_7" in read_entities(out / "sim.rrd")

    client = MlflowClient(sqlite_uri(iiwa_run / "mlruns.db"))
    (run,) = client.search_runs(
        [client.get_experiment_by_name("prg-tasks").experiment_id], "tags.`prg.task` = 'simulate'"
    )
    assert run.data.tags["prg.robot"] == "iiwa"
    assert run.data.metrics["simulate/tracking_error_mean_mm"] == pytest.approx(
        metrics["tracking_error_mean_mm"]
    )
    artifacts = {Path(a.path).name for a in client.list_artifacts(run.info.run_id, "simulate")}
    assert artifacts >= OUTPUTS
    assert "config.yaml" in {a.path for a in client.list_artifacts(run.info.run_id)}


def test_text_runs_prg_write_first_with_its_options(tmp_path, untrained_muse_checkpoint):
    out = tmp_path / "out"
    out.mkdir()
    (out / "sim.rrd").write_text("an earlier word's recording")  # stale with record=false
    (out / "notes.txt").write_text("the user's own file")
    result = simulate_cli(
        "text=a",
        f"ckpt={untrained_muse_checkpoint}",
        "generate.speed_cm_s=10",
        "layout.letter_height=2.0",
        f"out_dir={out}",
        f"paths.root_dir={tmp_path}",
        "mlflow=false",
        "record=false",
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert {p.name for p in (out / "word").iterdir()} == {
        "word.json",
        "word.png",
        "word.svg",
        "dmp_rollout.csv",
        "motion.csv",
    }
    assert OUTPUTS - {p.name for p in out.iterdir()} == {"sim.rrd"}  # record=false: removed
    assert (out / "notes.txt").read_text() == "the user's own file"
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["text"] == "a"
    assert metrics["word_height_cm"] <= 2.0 + 1e-6
    assert metrics["tracking_error_mean_mm"] < 0.5


RERUN_FOV_Y = np.radians(55.0)  # Rerun's 3D eye: its vertical field of view


def _picture(view: dict, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where ``points`` (world) appear in a 3D view's eye: tangents across and up (the edge of
    the picture is at tan(fov/2) up and down); every point must lie in front of the eye."""
    position = np.array(view["EyeControls3D:position"])
    forward = np.array(view["EyeControls3D:look_target"]) - position
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, view["EyeControls3D:eye_up"])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    rel = np.asarray(points) - position
    depth = rel @ forward
    assert np.all(depth > 0)
    return rel @ right / depth, rel @ up / depth


def test_the_views_open_on_the_arm_the_page_the_word_and_a_clear_joint_plot(iiwa_run):
    """The stored blueprint frames what the recording holds: the robot view the arm's base, its
    pen's whole path and the page's corners; the close-up the ink, large; the page view the ink;
    the joint plot's legend beside the curves, not over them."""
    from scipy.spatial.transform import Rotation

    from prg.recording.simulation import VIEW_ASPECT

    out = _iiwa_folder(iiwa_run)
    rrd = out / "sim.rrd"
    views = read_views(rrd)
    data = np.load(out / "joints.npz")
    ink_world = data["tip_world"][data["contact"]]
    ((centre,),) = read_component(rrd, "world/paper", "Boxes3D:centers")
    ((half,),) = read_component(rrd, "world/paper", "Boxes3D:half_sizes")
    ((quaternion,),) = read_component(rrd, "world/paper", "Boxes3D:quaternions")
    corners = np.array([[sx, sy, 1] for sx in (-1, 1) for sy in (-1, 1)]) * half
    page = Rotation.from_quat(quaternion).apply(corners) + centre
    ((base,),) = read_component(rrd, "world/lbr_iiwa/base", "Transform3D:translation")

    edge = np.tan(RERUN_FOV_Y / 2)
    robot = views["iiwa writes 'ok'"]
    across, up = _picture(robot, np.vstack([page, [base], data["tip_world"]]))
    assert np.abs(across).max() <= edge * VIEW_ASPECT and np.abs(up).max() <= edge
    assert np.ptp(up) > edge / 2  # not lost in the distance: over a quarter of the picture

    close_up = views["Pen on the page"]
    across, up = _picture(close_up, ink_world)
    assert np.abs(across).max() <= edge * VIEW_ASPECT and np.abs(up).max() <= edge
    assert max(np.ptp(across) / VIEW_ASPECT, np.ptp(up)) > edge / 2  # over a quarter of it
    word_in_robot_view = np.ptp(_picture(robot, ink_world)[0])
    assert np.ptp(across) > 10 * word_in_robot_view

    bounds = views["Ink on the page (cm)"]["VisualBounds2D:range"]
    ink_page = data["tip_paper"][data["contact"], :2] * [1, -1]  # logged y-flipped
    (x0, x1), (y0, y1) = bounds["x_range"], bounds["y_range"]
    assert x0 < ink_page[:, 0].min() and ink_page[:, 0].max() < x1
    assert y0 < ink_page[:, 1].min() and ink_page[:, 1].max() < y1

    joints = views["Joint angles (rad)"]
    assert joints["PlotLegend:visible"] is True
    assert joints["PlotLegend:corner"] == rrb.Corner2D.RightTop.value
    last = read_times(rrd, f"joints/{data['joint_names'][0]}", "sim_time")[-1]
    shown = joints["TimeAxis:view_range"]
    assert shown["start"] == 0 and shown["end"] / 1e9 > 1.25 * last  # room right of the curves


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["word=/nonexistent/word.json"], "no such word trajectory file"),
        (["word={word}", "robot=kuka"], "robot"),
        (["word={word}", "scale=40", "workspace_step_cm=4"], r"at most [\d.]+ cm wide fits panda"),
    ],
    ids=["missing", "unknown-robot", "too-large"],
)
def test_bad_input_gets_one_line_exit_2_and_nothing_written(tmp_path, word_json, args, message):
    out = tmp_path / "out"
    result = simulate_cli(
        *[a.format(word=word_json) for a in args],
        f"out_dir={out}",
        f"paths.root_dir={tmp_path}",
        "mlflow=false",
    )
    assert result.returncode == 2, result.stderr[-2000:]
    lines = [line for line in result.stderr.splitlines() if line.startswith("prg-simulate")]
    assert len(lines) == 1 and "Traceback" not in result.stderr
    assert re.search(message, lines[0]), lines[0]
    assert not out.exists()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["word={bad}"], "not valid JSON"),
        ([], "nothing to write"),
        (["word={word}", "text=ok"], "both give the word"),
        (["word={word}", "control.steps_per_waypoint=0"], "steps_per_waypoint"),
        (["word={word}", "ik.method=fast"], "ik.method"),
        (["word={word}", "gui=true"], "needs a display"),
    ],
    ids=["not-json", "no-word", "both", "bad-setting", "bad-ik-method", "gui-without-display"],
)
def test_the_task_refuses_bad_input_before_writing_anything(
    tmp_path, word_json, monkeypatch, args, message
):
    from prg.commands.cli import compose_config
    from prg.commands.simulate import simulate
    from prg.errors import UsageError

    monkeypatch.setenv("DISPLAY", "")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    out = tmp_path / "out"
    cfg = compose_config(
        "simulate",
        [
            *[a.format(word=word_json, bad=bad) for a in args],
            f"out_dir={out}",
            f"paths.root_dir={tmp_path}",
            "mlflow=false",
            "progress=false",
        ],
    )
    with pytest.raises(UsageError, match=message):
        simulate(cfg)
    assert not out.exists()
