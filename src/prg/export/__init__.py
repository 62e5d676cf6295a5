"""From the screen to paper: a written word as files real machines take.

``prg.export.export_word(word, ExportSettings(formats=("gcode", "mcap")), "out/")`` writes a
:class:`~prg.pipeline.word.WordTrajectory` for pen plotters and robot arms (``prg-export`` is
the command).

Modules
-------
:mod:`prg.export.plotter`
    Pen plotters: G-code for GRBL (the DMP's timing as per-move feed rates), HPGL and plotter
    SVG (through vpype), at true size on a sheet, refused when the word does not fit.
:mod:`prg.export.robot`
    Robot arms: the simulated arm's commanded joint trajectory and the pen tip's path in the
    robot base frame, as ROS 2 messages in an MCAP file and as CSV.
:mod:`prg.export.limits`
    Safe to send: joint positions, velocity, acceleration and jerk against the arm's limits
    (a uniform slow-down when that fits), and the pen's contact with the paper.
:mod:`prg.export.ros`
    The ROS 2 message definitions the MCAP file carries, and the messages as dicts.
:mod:`prg.export.run`
    :func:`export_word`: every output made in memory, then written together (all or nothing).
"""

from __future__ import annotations

from prg.export.limits import (
    ContactCheck,
    JointLimits,
    LimitSettings,
    TimingCheck,
    check_contact,
    check_timing,
)
from prg.export.plotter import GcodeSettings, HpglSettings, PlotterSettings
from prg.export.robot import RobotTrajectory, robot_trajectory, write_csv, write_mcap
from prg.export.run import FILES, FORMATS, ExportResult, ExportSettings, export_word

__all__ = [
    "FILES",
    "FORMATS",
    "ContactCheck",
    "ExportResult",
    "ExportSettings",
    "GcodeSettings",
    "HpglSettings",
    "JointLimits",
    "LimitSettings",
    "PlotterSettings",
    "RobotTrajectory",
    "TimingCheck",
    "check_contact",
    "check_timing",
    "export_word",
    "robot_trajectory",
    "write_csv",
    "write_mcap",
]
