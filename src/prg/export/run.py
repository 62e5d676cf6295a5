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
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from prg.checks import EXPORT_RANGES
from prg.errors import UsageError
from prg.export.limits import JointLimits, LimitSettings
from prg.export.plotter import (
    GcodeSettings,
    HpglSettings,
    PlotterSettings,
    gcode_text,
    hpgl_text,
    ink_strokes,
    place_word,
    svg_text,
    timed_strokes,
)
from prg.fields import check, check_ranges
from prg.files import staged_outputs, write_json, write_text

if TYPE_CHECKING:
    from prg.export.robot import RobotTrajectory
    from prg.pipeline.word import WordTrajectory
    from prg.sim import RobotSettings, SimResult, SimSettings

log = logging.getLogger(__name__)

__all__ = ["FILES", "FORMATS", "ExportResult", "ExportSettings", "export_word"]

FILES = {
    "gcode": "word.gcode",
    "hpgl": "word.hpgl",
    "svg": "word.svg",
    "mcap": "word.mcap",
    "csv": "word.csv",
}
FORMATS = tuple(FILES)
PLOTTER_FORMATS = ("gcode", "hpgl", "svg")
ROBOT_FORMATS = ("mcap", "csv")
TIMED_FORMATS = ("gcode", "mcap", "csv")


def check_formats(formats: Any) -> tuple[str, ...]:
    """``formats`` as a tuple of known format names (one name alone is accepted)."""
    if isinstance(formats, str):
        formats = [formats]
    if not isinstance(formats, Sequence) or not formats:
        raise UsageError(f"formats must be a list of {', '.join(FORMATS)}, got {formats!r}")
    names = []
    for name in formats:
        if name not in FORMATS:
            raise UsageError(f"formats: unknown format {name!r}: accepted are {', '.join(FORMATS)}")
        if name not in names:
            names.append(name)
    return tuple(names)


@dataclass(frozen=True)
class ExportSettings:
    """What to export and how.

    Attributes
    ----------
    formats : tuple of str
        Any of ``gcode``, ``hpgl``, ``svg`` (pen plotters) and ``mcap``, ``csv`` (robot arms).
    tempo : float
        Multiplies the DMP's duration for the plotter (2: twice as slow); the arm's is
        ``sim.tempo``.
    sample_dt_s : float
        Spacing of the DMP rollout the G-code follows (one move per step).
    plotter, gcode, hpgl : PlotterSettings, GcodeSettings, HpglSettings
    robot : RobotSettings or None
        The arm (robot formats); None: the Panda of ``conf/robot/panda.yaml``.
    sim : SimSettings or None
        The simulation that computes the arm's trajectory (paper, placement, motion, IK ...);
        None: ``conf/simulate.yaml``'s defaults.
    limits : LimitSettings
    datasheets : mapping of str to mapping
        Per robot name, its datasheet limits (:meth:`JointLimits.from_mapping`); a robot
        without one is checked against its URDF alone.
    """

    formats: tuple[str, ...] = FORMATS
    tempo: float = 1.0
    sample_dt_s: float = 0.01
    plotter: PlotterSettings = field(default_factory=PlotterSettings)
    gcode: GcodeSettings = field(default_factory=GcodeSettings)
    hpgl: HpglSettings = field(default_factory=HpglSettings)
    robot: RobotSettings | None = None
    sim: SimSettings | None = None
    limits: LimitSettings = field(default_factory=LimitSettings)
    datasheets: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "formats", check_formats(self.formats))
        check_ranges(self, EXPORT_RANGES)
        check(isinstance(self.datasheets, Mapping), "datasheets", "must map robot names to limits")

    def datasheet(self, robot: RobotSettings) -> JointLimits | None:
        """The datasheet limits of ``robot`` (None if there are none)."""
        node = self.datasheets.get(robot.name)
        if node is None:
            return None
        from prg.errors import SettingsError

        try:
            return JointLimits.from_mapping(robot.arm_joints, node)
        except SettingsError as err:
            raise err.under(f"limits.joints.{robot.name}") from None


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
