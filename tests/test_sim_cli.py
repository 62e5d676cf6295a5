"""`prg-simulate`: word.json or text -> ink, page render, joints, metrics, sim.rrd, MLflow run;
bad input gets one line, exit code 2, and nothing is written."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from mlflow import MlflowClient

from prg.recording import read_entities
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


def test_simulates_a_word_json_into_every_output_and_an_mlflow_run(tmp_path, word_json):
    out = tmp_path / "out"
    result = simulate_cli(
        f"word={word_json}", f"out_dir={out}", f"paths.root_dir={tmp_path}", "robot=iiwa"
    )
    assert result.returncode == 0, result.stderr[-2000:]
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

    client = MlflowClient(sqlite_uri(tmp_path / "mlruns.db"))
    (run,) = client.search_runs(
        [client.get_experiment_by_name("prg").experiment_id], "tags.`prg.task` = 'simulate'"
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
