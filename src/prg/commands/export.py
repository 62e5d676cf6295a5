"""``prg-export``: a written word to real machines — pen plotters and robot arms.

Examples
--------
``prg-export word=outputs/write/muse/hello-20261202-120000/word.json``               every format
``prg-export word=word.json formats=[gcode] gcode.pen=servo``        GRBL pen plotter, servo pen
``prg-export word=word.json formats=[hpgl] hpgl.device=hp7440a``
``prg-export word=word.json formats=[mcap,csv] robot=iiwa tempo=2``  ROS 2 MCAP and CSV

Reads a ``word.json`` written by ``prg-write`` and writes into ``out_dir`` ``word.gcode`` (GRBL,
feed rates from the DMP's timing), ``word.hpgl`` (vpype device profile), ``word.svg`` (plotter
SVG, true size), ``word.mcap`` (ROS 2: the arm's joint trajectory and the pen tip's path in the
robot base frame) and ``word.csv`` (the same per waypoint), as ``formats`` asks, and
``export.json`` (placement, pen-down time, the joint-limit check and its slow-down). The robot
formats run the simulated arm first (:func:`prg.sim.simulate_word`, the settings of
``conf/simulate.yaml``, which ``conf/export.yaml`` extends): its IK solution of every waypoint is
the commanded trajectory, checked against the arm's limits before anything is written
(:mod:`prg.export.limits`). Every output is made first and written together (a staging folder),
so a refusal writes nothing. The work is :func:`prg.export.export_word`'s.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

from omegaconf import DictConfig, OmegaConf

from prg.checks import check_values
from prg.commands.cli import check_output
from prg.commands.settings import node
from prg.errors import SettingsError, UsageError
from prg.files import folder_fields, word_folder
from prg.pipeline.word import WordTrajectory

log = logging.getLogger(__name__)

_SIM_NODES = ("paper", "motion", "control", "ik")


def _under(key: str, build):
    try:
        return build()
    except SettingsError as err:
        raise err.under(key) from None


def export_settings(cfg: DictConfig) -> Any:
    """The config as :class:`prg.export.ExportSettings` (a refused value named by its key)."""
    from prg.export import ExportSettings, GcodeSettings, HpglSettings, LimitSettings
    from prg.export.plotter import PlotterSettings
    from prg.sim import RobotSettings, SimSettings

    limits = node(cfg, "limits")
    datasheets = limits.pop("joints", None) or {}
    formats = cfg.formats
    if OmegaConf.is_list(formats):
        formats = OmegaConf.to_container(formats, resolve=True)
    plotter = node(cfg, "plotter") | {"scale": cfg.scale}
    sim_values = {key: node(cfg, key) for key in _SIM_NODES}
    sim_values |= {key: cfg[key] for key in ("scale", "tempo", "workspace_step_cm")}
    return ExportSettings(  # its own fields are top-level keys: formats, tempo, sample_dt_s
        formats=formats,
        tempo=cfg.tempo,
        sample_dt_s=cfg.sample_dt_s,
        plotter=_under("plotter", lambda: PlotterSettings.from_mapping(plotter)),
        gcode=_under("gcode", lambda: GcodeSettings.from_mapping(node(cfg, "gcode"))),
        hpgl=_under("hpgl", lambda: HpglSettings.from_mapping(node(cfg, "hpgl"))),
        robot=_under("robot", lambda: RobotSettings.from_dict(node(cfg, "robot"))),
        sim=SimSettings.from_mapping(sim_values),
        limits=_under("limits", lambda: LimitSettings.from_mapping(limits)),
        datasheets=datasheets,
    )


def export(cfg: DictConfig) -> tuple[Any, Path]:
    """Task: read the word, export it to the formats asked for, into ``out_dir``.

    Returns
    -------
    result : prg.export.ExportResult
    out_dir : Path
    """
    from prg.export import export_word

    check_values(cfg)
    if cfg.word is None:
        raise UsageError("nothing to export: give word=WORD.json (written by prg-write)")
    settings = export_settings(cfg)
    folder_fields(cfg.out_dir)
    check_output(cfg.out_dir, "out_dir")
    word = WordTrajectory.from_json(Path(cfg.word))
    with word_folder(cfg.out_dir, word.text) as out_dir:
        result = export_word(word, settings, out_dir)
    robot = result.metadata.get("robot")
    if robot is not None:
        log.info(
            "%s: %s; %.1f s, pen down %.1f s",
            robot["robot"],
            result.trajectory.timing.describe(),
            robot["duration_s"],
            robot["pen_down_s"],
        )
    gcode = result.metadata.get("plotter", {}).get("gcode")
    if gcode is not None:
        log.info(
            "G-code: %d moves, pen down %.2f s, fastest feed %.0f mm/min",
            gcode["moves"],
            gcode["pen_down_s"],
            gcode["max_feed_mm_min"],
        )
    log.info("exported %r as %s -> %s", word.text, ", ".join(settings.formats), out_dir)
    return result, out_dir


if __name__ == "__main__":
    from prg.commands.entry import export

    export()
