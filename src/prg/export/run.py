"""The export as one call: a written word to the files of the chosen machines, all or nothing.

:func:`export_word` makes every requested output in memory first — plotter programs from the
word itself, robot files from a simulation of the arm writing it (:func:`prg.sim.simulate_word`:
the IK of every waypoint is the commanded trajectory; the check of :mod:`prg.export.limits` runs
on it) — so a refusal (the word off the paper, a joint limit, a missing DMP) writes nothing; the
files are then written into a staging folder and moved into the output folder together
(:func:`prg.files.staged_outputs`), with ``export.json`` saying what was written and measured.
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from prg.errors import UsageError
from prg.export.plotter import (
    gcode_text,
    hpgl_text,
    ink_strokes,
    place_word,
    svg_text,
    timed_strokes,
)
from prg.export.settings import FILES, FORMATS, ExportSettings
from prg.files import staged_outputs, write_json, write_text

if TYPE_CHECKING:
    from prg.export.robot import RobotTrajectory
    from prg.pipeline.word import WordTrajectory
    from prg.sim import SimResult

log = logging.getLogger(__name__)

__all__ = ["FILES", "FORMATS", "ExportResult", "ExportSettings", "export_word"]

PLOTTER_FORMATS = ("gcode", "hpgl", "svg")
ROBOT_FORMATS = ("mcap", "csv")
TIMED_FORMATS = ("gcode", "mcap", "csv")


@dataclass
class ExportResult:
    """What :func:`export_word` wrote.

    Attributes
    ----------
    files : dict of str to Path
        Format -> file written (and ``json`` -> ``export.json``).
    metadata : dict
        The content of ``export.json``.
    trajectory : RobotTrajectory or None
        The checked arm trajectory (robot formats).
    simulation : SimResult or None
    """

    files: dict[str, Path]
    metadata: dict[str, Any]
    trajectory: RobotTrajectory | None = None
    simulation: SimResult | None = None


def _plotter_outputs(
    word: WordTrajectory, settings: ExportSettings
) -> tuple[dict[str, str], dict[str, Any]]:
    wanted = [f for f in settings.formats if f in PLOTTER_FORMATS]
    if not wanted:
        return {}, {}
    placement = place_word(word, settings.plotter)
    ink = [placement(s) for s in ink_strokes(word)]
    texts: dict[str, str] = {}
    low = min(s.min(axis=0)[0] for s in ink), min(s.min(axis=0)[1] for s in ink)
    high = max(s.max(axis=0)[0] for s in ink), max(s.max(axis=0)[1] for s in ink)
    meta: dict[str, Any] = {
        "paper_mm": list(settings.plotter.paper_mm),
        "mm_per_word_cm": placement.mm_per_cm,
        "ink_box_mm": [list(low), list(high)],
        "ink_strokes": len(ink),
    }
    if "svg" in wanted:
        texts["svg"] = svg_text(ink, settings.plotter, word.text)
    if "hpgl" in wanted:
        texts["hpgl"] = hpgl_text(ink, settings.plotter, settings.hpgl, word.text)
        meta["hpgl_device"] = settings.hpgl.device
    if "gcode" in wanted:
        strokes = timed_strokes(word, placement, settings.sample_dt_s, settings.tempo)
        program = gcode_text(strokes, settings.plotter, settings.gcode, word.text)
        texts["gcode"] = program.text
        meta["gcode"] = {
            "pen_down_s": program.pen_down_s,
            "moves": program.moves,
            "strokes": program.strokes,
            "max_feed_mm_min": program.max_feed_mm_min,
            "tempo": settings.tempo,
            "sample_dt_s": settings.sample_dt_s,
            "pen": settings.gcode.pen,
            "origin_mm": list(settings.gcode.origin_mm),
        }
    return texts, meta


def _robot_trajectory(
    word: WordTrajectory, settings: ExportSettings
) -> tuple[RobotTrajectory, SimResult]:
    from prg.export.robot import robot_trajectory
    from prg.sim import RobotSettings, SimSettings, simulate_word

    robot = settings.robot or RobotSettings.named("panda")
    sim = settings.sim or SimSettings()
    datasheet = settings.datasheet(robot)  # a bad datasheet is refused before the simulation
    result = simulate_word(word, robot, sim, render=False)
    return robot_trajectory(result, datasheet, settings.limits), result


def export_word(
    word: WordTrajectory,
    settings: ExportSettings | None = None,
    out_dir: str | os.PathLike | None = None,
) -> ExportResult:
    """Export ``word`` to the files of ``settings.formats`` in ``out_dir``.

    Parameters
    ----------
    word : WordTrajectory
        From ``prg-write`` (``word.json``); the timed formats (G-code, MCAP, CSV) need its DMP.
    settings : ExportSettings, optional
    out_dir : path, optional
        Output folder (created; files of other names in it are kept). None: nothing is written,
        the result holds the metadata and the trajectory only.

    Returns
    -------
    ExportResult

    Raises
    ------
    UsageError
        One line, before anything is written: a word without a DMP for a timed format, a word
        off the paper or out of a plotter's reach, a feed above the machine's, an unknown
        plotter or paper, a joint trajectory outside the arm's limits (or needing more
        slow-down than allowed), a pen that would not touch the paper or press too far.
    """
    settings = settings or ExportSettings()
    timed = [f for f in settings.formats if f in TIMED_FORMATS]
    if timed and word.dmp is None:
        raise UsageError(
            f"word {word.text[:40]!r} has no DMP: {', '.join(timed)} follow the DMP's timing; "
            "write the word with prg-write (svg and hpgl need no timing)"
        )
    texts, plotter_meta = _plotter_outputs(word, settings)
    trajectory = simulation = None
    metadata: dict[str, Any] = {
        "text": word.text,
        "formats": list(settings.formats),
        "files": {f: FILES[f] for f in settings.formats},
    }
    if plotter_meta:
        metadata["plotter"] = plotter_meta
    if any(f in ROBOT_FORMATS for f in settings.formats):
        trajectory, simulation = _robot_trajectory(word, settings)
        metadata["robot"] = trajectory.metadata() | {
            "tempo": simulation.settings.tempo,
            "scale": simulation.settings.scale,
            "placement": simulation.placement,
            "ik_error_max_mm": float(simulation.ik_error_m.max() * 1000.0),
        }
    files: dict[str, Path] = {}
    if out_dir is not None:
        out_dir = Path(out_dir)
        with staged_outputs(out_dir) as staging:
            for name, text in texts.items():
                write_text(staging / FILES[name], text, atomic=False)
            if trajectory is not None:
                from prg.export.robot import write_csv, write_mcap

                if "mcap" in settings.formats:
                    write_mcap(trajectory, staging / FILES["mcap"])
                if "csv" in settings.formats:
                    write_csv(trajectory, staging / FILES["csv"])
            write_json(staging / "export.json", metadata)
        files = {f: out_dir / FILES[f] for f in settings.formats} | {
            "json": out_dir / "export.json"
        }
    return ExportResult(files, metadata, trajectory, simulation)
