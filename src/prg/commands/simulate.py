"""``prg-simulate``: a simulated 7-DOF arm writes the word on paper (PyBullet), recorded in Rerun.

Examples
--------
``prg-simulate text=joy``                          runs ``prg-write`` first (MUSE), Panda arm
``prg-simulate word=outputs/write/write-muse/word.json robot=iiwa``
``prg-simulate text="hello world" scale=0.8 progress=false mlflow=false``
``prg-simulate text=joy gui=true``                 PyBullet's GUI (needs a display)

The word comes from ``word=`` (a ``word.json`` written by ``prg-write``) or from ``prg-write``
itself, run first with every one of its options (``text``, ``audio``, ``images``,
``trajectories``, ``family``, ``generate.*`` ...). The robot (``robot=panda|iiwa``,
``conf/robot/``) writes it on a sheet on the table: approach with the pen up, the DMP rollout
with the pen down at the DMP's tempo, lift between words and retreat at the end
(:func:`prg.sim.simulate_word`). A word that does not fit the arm's reachable workspace on the
paper is refused with one line giving the size that fits.

Writes into ``out_dir`` (atomically, through a staging folder): ``ink.png`` and ``ink.svg`` (the
ink, true to scale), ``page.png`` (a TinyRenderer camera picture of the page), ``joints.csv`` and
``joints.npz`` (the joint trajectory, pen tip and ink per physics step), ``metrics.json``
(tracking error mean/max in mm between commanded and inked path, longest ink gap, simulated and
wall time, their ratio, robot, word size), ``sim.rrd`` (Rerun: ``rerun sim.rrd``) and ``word/``
(the word written); with ``mlflow=true`` an MLflow run (tag ``prg.task=simulate``) holding them.
"""

from __future__ import annotations

import dataclasses
import logging
import shutil
from pathlib import Path
from typing import Any

import numpy as np
from omegaconf import DictConfig, OmegaConf

from prg.checks import check_values, literal_text
from prg.commands.cli import check_output, hydra_command
from prg.commands.settings import writer_from_config
from prg.errors import UsageError
from prg.files import staged_outputs, write_json
from prg.pipeline.word import WordTrajectory
from prg.tracking import task_run

log = logging.getLogger(__name__)

CHANNELS = ("text", "audio", "images", "trajectories")
OUTPUTS = ("ink.png", "ink.svg", "page.png", "joints.csv", "joints.npz", "metrics.json")


def settings_from_config(cfg: DictConfig):
    """The robot (:class:`~prg.sim.robots.RobotSettings`) and the simulation settings
    (:class:`~prg.sim.writing.SimSettings`) of the composed config; one line on a bad value."""
    from prg.sim import (
        Camera,
        ControlSettings,
        IKSettings,
        MotionSettings,
        Paper,
        RobotSettings,
        SimSettings,
    )

    def node(key: str, cls: type | None = None) -> dict[str, Any]:
        """The config node ``key``; a numeric field of ``cls`` must hold a number."""
        values = OmegaConf.to_container(cfg[key], resolve=True)
        types = {f.name: f.type for f in dataclasses.fields(cls)} if cls else {}
        for name, value in values.items():
            kind = types.get(name)
            if kind in ("int", "float") or (kind == "float | None" and value is not None):
                _number(value, f"{key}.{name}")
        return values

    paper = node("paper")
    word_centre = paper.pop("word_centre_cm")
    try:
        robot = RobotSettings.from_dict(node("robot"))
        settings = SimSettings(
            paper=Paper(
                size_cm=tuple(paper["size_cm"]),
                centre=tuple(paper["centre"]),
                yaw_deg=_number(paper["yaw_deg"], "paper.yaw_deg"),
                thickness_m=_number(paper["thickness_m"], "paper.thickness_m"),
            ),
            motion=MotionSettings(**node("motion", MotionSettings)),
            control=ControlSettings(**node("control", ControlSettings)),
            ik=IKSettings(**node("ik", IKSettings)),
            camera=Camera(**node("camera", Camera)),
            scale=_number(cfg.scale, "scale"),
            word_centre_cm=tuple(word_centre),
            tempo=_number(cfg.tempo, "tempo"),
            workspace_step_cm=_number(cfg.workspace_step_cm, "workspace_step_cm"),
        )
    except (TypeError, ValueError, KeyError) as err:
        if isinstance(err, UsageError):
            raise
        raise UsageError(f"simulate settings: {err}") from None
    return robot, settings


def _number(value: Any, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise UsageError(f"{key} must be a number, got {value!r}")
    return float(value)


def simulate(cfg: DictConfig) -> tuple[Any, Path]:
    """Task: get the word, simulate the robot writing it, save the outputs (and an MLflow run).

    Returns
    -------
    result : prg.sim.SimResult
    out_dir : Path
    """
    from prg.sim import simulate_word

    check_values(cfg)
    channels = [c for c in CHANNELS if cfg.get(c) is not None]
    if cfg.word is not None and channels:
        raise UsageError(
            f"word= and {channels[0]}= both give the word: give word=WORD.json (from prg-write) "
            f"or {'/'.join(CHANNELS)}= (prg-write runs first)"
        )
    if cfg.word is None and not channels:
        raise UsageError(
            "nothing to write: give word=WORD.json (from prg-write) or text=WORD "
            "(prg-write runs first; also audio=, images=, trajectories=)"
        )
    robot, settings = settings_from_config(cfg)
    out_dir = check_output(cfg.out_dir, "out_dir")
    given = None
    if cfg.word is not None:
        given = Path(cfg.word)
        word = WordTrajectory.from_json(given)
    else:
        text = literal_text(cfg.text, "text")
        writer = writer_from_config(cfg)
    tags = {"prg.robot": robot.name}
    with task_run(cfg, "simulate", tags, enabled=cfg.mlflow) as run:
        with staged_outputs(out_dir) as staging:
            if given is None:
                written = writer.write(text, cfg.audio, cfg.images, cfg.trajectories)
                written.save(staging / "word", record=cfg.record)
                word = written.word
            else:
                (staging / "word").mkdir()
                shutil.copyfile(given, staging / "word" / "word.json")
            result = simulate_word(word, robot, settings, gui=cfg.gui, progress=cfg.progress)
            save_outputs(result, staging, record=cfg.record)
        m = result.metrics
        log.info(
            "%s wrote %r (%.1f x %.1f cm): tracking error mean %.4f mm, max %.4f mm; %.1f s "
            "simulated in %.1f s -> %s",
            robot.name,
            word.text,
            m["word_width_cm"],
            m["word_height_cm"],
            m["tracking_error_mean_mm"],
            m["tracking_error_max_mm"],
            m["sim_s"],
            m["wall_s"] + m["ik_wall_s"],
            out_dir,
        )
        if run is not None:
            _log_run(run, cfg, result, out_dir, given)
    return result, out_dir


def save_outputs(result, folder: Path, record: bool = True) -> None:
    """``ink.png``, ``ink.svg``, ``page.png``, ``joints.csv``, ``joints.npz``, ``metrics.json``
    and (``record``) ``sim.rrd`` of a :class:`~prg.sim.SimResult` into ``folder``."""
    from PIL import Image

    from prg.sim import ink_png, ink_svg, record_simulation

    folder = Path(folder)
    strokes = result.ink_strokes()
    ink_png(strokes, folder / "ink.png")
    ink_svg(strokes, folder / "ink.svg", title=f"{result.text} ({result.robot.name})")
    if result.page is not None:
        Image.fromarray(result.page).save(folder / "page.png")
    names = result.arm_joint_names
    columns = np.column_stack(
        [result.t, result.q, result.tip_paper, result.contact.astype(np.float64)]
    )
    header = ",".join(["t_s", *names, "tip_x_cm", "tip_y_cm", "tip_height_cm", "ink"])
    fmt = ["%.6f"] + ["%.8f"] * len(names) + ["%.6f"] * 3 + ["%d"]
    np.savetxt(folder / "joints.csv", columns, delimiter=",", header=header, comments="", fmt=fmt)
    np.savez_compressed(
        folder / "joints.npz",
        t=result.t,
        joint_names=np.array(names),
        q=result.q,
        q_target=result.q_target,
        tip_world=result.tip_world,
        tip_quaternion=result.tip_quaternion,
        tip_paper=result.tip_paper,
        commanded=result.commanded,
        contact=result.contact,
        plan_t=result.plan.t,
        plan_tip=result.plan.tip,
        plan_pen_down=result.plan.pen_down,
        plan_stroke=result.plan.stroke,
        plan_phase=result.plan.phase,
        q_plan=result.q_plan,
    )
    write_json(folder / "metrics.json", result.metrics)
    if record:
        record_simulation(folder / "sim.rrd", result)


def _log_run(run, cfg: DictConfig, result, out_dir: Path, given: Path | None) -> None:
    run.client.set_tag(run.run_id, "prg.text", result.text)
    params: dict[str, Any] = {
        "robot": result.robot.name,
        "text": result.text,
        "word": str(given) if given else "prg-write",
    }
    for key in ("scale", "tempo", "workspace_step_cm"):
        params[key] = cfg[key]
    for group in ("paper", "motion", "control", "ik"):
        params[group] = OmegaConf.to_container(cfg[group], resolve=True)
    run.log_params(params)
    run.log_metrics(result.metrics, prefix="simulate/")
    run.log_text(OmegaConf.to_yaml(cfg, resolve=True), "config.yaml")
    run.log_artifacts(out_dir, "simulate")


main = hydra_command(simulate, "simulate", "prg-simulate")

if __name__ == "__main__":
    main()
