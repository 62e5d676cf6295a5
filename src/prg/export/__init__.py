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
:mod:`prg.export.settings`
    The settings classes (:class:`ExportSettings` and the plotter, G-code, HPGL and limit
    settings), without numpy: ``prg-export`` checks its config against their declared ranges
    before loading it.

The names below are imported from their modules on first use (``from prg.export import
ExportSettings`` loads no numpy), so that importing the package, as importing
:mod:`prg.export.settings` does, stays light.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from prg.export.limits import (
        ContactCheck,
        JointLimits,
        TimingCheck,
        check_contact,
        check_timing,
    )
    from prg.export.robot import RobotTrajectory, robot_trajectory, write_csv, write_mcap
    from prg.export.run import ExportResult, export_word
    from prg.export.settings import (
        FILES,
        FORMATS,
        ExportSettings,
        GcodeSettings,
        HpglSettings,
        LimitSettings,
        PlotterSettings,
    )

_MODULES = {  # each exported name -> the module that defines it (imported on first use)
    "FILES": "settings",
    "FORMATS": "settings",
    "ExportSettings": "settings",
    "GcodeSettings": "settings",
    "HpglSettings": "settings",
    "LimitSettings": "settings",
    "PlotterSettings": "settings",
    "ContactCheck": "limits",
    "JointLimits": "limits",
    "TimingCheck": "limits",
    "check_contact": "limits",
    "check_timing": "limits",
    "RobotTrajectory": "robot",
    "robot_trajectory": "robot",
    "write_csv": "robot",
    "write_mcap": "robot",
    "ExportResult": "run",
    "export_word": "run",
}

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


def __getattr__(name: str) -> Any:
    """An exported name, imported from its module the first time it is asked for."""
    module = _MODULES.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_MODULES))
