"""The simulated writing robot: a 7-DOF arm in PyBullet writes a word on paper.

Modules
-------
:mod:`prg.sim.geometry`
    Pure numeric core: the paper frame, word placement, pen-down samples, contact-band ink,
    tracking error, ink gaps.
:mod:`prg.sim.plan`
    The pen's timed waypoints: approach, lower, write (DMP timing), lift, travel, retreat.
:mod:`prg.sim.robots`
    Robot descriptions as data (``conf/robot/*.yaml``).
:mod:`prg.sim.scene`
    The PyBullet scene (one client id, no global state) and the IK solver.
:mod:`prg.sim.writing`
    :func:`simulate_word`: workspace check, IK, position control, ink, metrics.
:mod:`prg.sim.ink`
    The ink as PNG, SVG and the paper's texture.
:mod:`prg.sim.record`
    The Rerun recording (URDF arm animated over ``sim_time``, pen path, ink, command).
:mod:`prg.sim.words`
    Words from a Hershey font, without a model (tests, benchmark, a first try).
"""

from __future__ import annotations

from prg.sim.geometry import (
    Paper,
    distance_to_polylines,
    in_contact,
    max_ink_gap,
    pen_down_samples,
    tracking_error,
)
from prg.sim.ink import ink_png, ink_svg
from prg.sim.plan import MotionPlan, MotionSettings, plan_motion
from prg.sim.record import record_simulation
from prg.sim.robots import RobotSettings
from prg.sim.scene import Camera, IKSettings, IKSolver, Scene, UnreachableError
from prg.sim.words import font_word
from prg.sim.writing import (
    ControlSettings,
    ReachMap,
    SimResult,
    SimSettings,
    check_workspace,
    simulate_word,
    word_samples,
)

__all__ = [
    "Camera",
    "ControlSettings",
    "IKSettings",
    "IKSolver",
    "MotionPlan",
    "MotionSettings",
    "Paper",
    "ReachMap",
    "RobotSettings",
    "Scene",
    "SimResult",
    "SimSettings",
    "UnreachableError",
    "check_workspace",
    "distance_to_polylines",
    "font_word",
    "in_contact",
    "ink_png",
    "ink_svg",
    "max_ink_gap",
    "pen_down_samples",
    "plan_motion",
    "record_simulation",
    "simulate_word",
    "tracking_error",
    "word_samples",
]
