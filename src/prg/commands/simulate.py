"""``prg-simulate``: a simulated 7-DOF arm writes the word on paper (PyBullet), recorded in Rerun.

Examples
--------
``prg-simulate text=joy``                          runs ``prg-write`` first (MUSE), Panda arm
``prg-simulate word=outputs/write/muse/joy-20250101-120000/word.json robot=iiwa``
``prg-simulate text="hello world" scale=0.8 progress=false mlflow=false``
``prg-simulate text=joy gui=true``                 PyBullet's GUI (needs a display)

The word comes from ``word=`` (a ``word.json`` written by ``prg-write``) or from ``prg-write``
itself, run first with every one of its options (``text``, ``audio``, ``images``,
``trajectories``, ``family``, ``generate.*`` ...). The robot (``robot=panda|iiwa``,
``conf/robot/``) writes it on a sheet on the table: approach with the pen up, the DMP rollout
with the pen down at the DMP's tempo, lift between words and retreat at the end
(:func:`prg.sim.simulate_word`). A word that does not fit the arm's reachable workspace on the
paper is refused with one line giving the size that fits.

Writes into ``out_dir`` (atomically, through a staging folder; by default a new folder per run,
``outputs/simulate/<robot>/<text>-<YYYYmmdd-HHMMSS>``, :func:`prg.files.word_folder`):
``ink.png`` and ``ink.svg`` (the ink, true to scale), ``page.png`` (a TinyRenderer camera picture
of the page), ``joints.csv`` and ``joints.npz`` (the joint trajectory, pen tip and ink per physics
step), ``metrics.json`` (tracking error mean/max in mm between commanded and inked path, longest
ink gap, simulated and wall time, their ratio, robot, word size), ``sim.rrd`` (Rerun:
``rerun sim.rrd``) and ``word/`` (the word written); with ``mlflow=true`` an MLflow run (tag
``prg.task=simulate``) holding them.
"""

from __future__ import annotations

import logging
import shutil
from pathlib import Path
from typing import Any

from omegaconf import DictConfig, OmegaConf

from prg.checks import check_values, literal_text
from prg.commands.cli import check_output
from prg.commands.settings import simulation_settings, writer_from_config
from prg.errors import UsageError
from prg.files import folder_fields, staged_outputs, word_folder
from prg.pipeline.word import WordTrajectory
from prg.recording import record_simulation
from prg.tracking import task_run

log = logging.getLogger(__name__)

CHANNELS = ("text", "audio", "images", "trajectories")
OUTPUTS = ("ink.png", "ink.svg", "page.png", "joints.csv", "joints.npz", "metrics.json")


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
    robot, settings = simulation_settings(cfg)
    folder_fields(cfg.out_dir)
    check_output(cfg.out_dir, "out_dir")
    given = None
    if cfg.word is not None:
        given = Path(cfg.word)
        word = WordTrajectory.from_json(given)
    else:
        text = literal_text(cfg.text, "text")
        writer = writer_from_config(cfg)
    tags = {"prg.robot": robot.name}
    with task_run(cfg, "simulate", tags, enabled=cfg.mlflow) as run:
        if given is None:
            written = writer.write(text, cfg.audio, cfg.images, cfg.trajectories)
            word = written.word
        with (
            word_folder(cfg.out_dir, word.text) as out_dir,
            staged_outputs(out_dir, owned=(*OUTPUTS, "sim.rrd", "word")) as staging,
        ):
            if given is None:
                written.save(staging / "word", record=cfg.record)
            else:
                (staging / "word").mkdir()
                shutil.copyfile(given, staging / "word" / "word.json")
            result = simulate_word(word, robot, settings, gui=cfg.gui, progress=cfg.progress)
            result.save(staging)
            if cfg.record:
                record_simulation(staging / "sim.rrd", result)
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


if __name__ == "__main__":
    from prg.commands.entry import simulate

    simulate()
