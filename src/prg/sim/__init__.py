"""The simulated writing robot: a 7-DOF arm in PyBullet writes a word on paper.

``prg.sim.simulate_word(word, "panda")`` writes a :class:`~prg.pipeline.word.WordTrajectory`
with the Panda and ``conf/simulate.yaml``'s settings (:class:`SimSettings`); a command builds its
settings with :meth:`SimSettings.from_mapping` and :meth:`RobotSettings.from_dict`.

Modules
-------
:mod:`prg.sim.geometry`
    Pure numeric core: the paper frame, word placement, pen-down samples, contact-band ink,
    tracking error, ink gaps.
:mod:`prg.sim.plan`
    The pen's timed waypoints: approach, lower, write (DMP timing), lift, travel, retreat.
:mod:`prg.sim.robots`
    Robot descriptions as data (``conf/robot/*.yaml``, :meth:`RobotSettings.named`).
:mod:`prg.sim.bullet`
    What the scene and the IK share of PyBullet: the module, loading the arm, the pen's pose.
:mod:`prg.sim.scene`
    The PyBullet scene (one client id, no global state) and its camera.
:mod:`prg.sim.ik`
    The IK solver: the pen vertical, on a kinematic copy of the arm in its own client.
:mod:`prg.sim.workspace`
    The reachable workspace on the paper; a word that does not fit is refused.
:mod:`prg.sim.settings`
    :class:`SimSettings` (``conf/simulate.yaml``'s defaults, :meth:`SimSettings.from_mapping`)
    and :class:`ControlSettings`.
:mod:`prg.sim.writing`
    :func:`simulate_word`: place, check the workspace, plan and solve the IK, write, render.
:mod:`prg.sim.ink`
    The ink as PNG, SVG and the paper's texture.
:mod:`prg.recording.simulation`
    The Rerun recording (URDF arm animated over ``sim_time``, pen path, ink, command).
:mod:`prg.sim.font`
    Words from a Hershey font, without a model (tests, benchmark, a first try).
"""

from __future__ import annotations

from prg.sim.font import font_word
from prg.sim.geometry import (
    Paper,
    distance_to_polylines,
    in_contact,
    max_ink_gap,
    pen_down_samples,
    tracking_error,
)
from prg.sim.ik import IKSettings, IKSolver, UnreachableError
from prg.sim.ink import ink_png, ink_svg
from prg.sim.plan import MotionPlan, MotionSettings, plan_motion
from prg.sim.robots import RobotSettings
from prg.sim.scene import Camera, Scene
from prg.sim.settings import ControlSettings, SimSettings
from prg.sim.workspace import ReachMap, check_workspace
from prg.sim.writing import SimResult, simulate_word, word_samples

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
    "simulate_word",
    "tracking_error",
    "word_samples",
]
