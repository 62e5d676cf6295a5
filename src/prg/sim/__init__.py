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
    Loading a robot description into PyBullet (:class:`LoadedRobot`), the URDF's path.
:mod:`prg.sim.bullet`
    What the scene and the IK share of PyBullet: the module, loading the arm, the pen's pose.
:mod:`prg.sim.scene`
    The PyBullet scene (one client id, no global state) and its camera.
:mod:`prg.sim.ik`
    The IK solver: the pen vertical, on a kinematic copy of the arm in its own client.
:mod:`prg.sim.workspace`
    The reachable workspace on the paper; a word that does not fit is refused.
:mod:`prg.sim.settings`
    The settings classes, without numpy or PyBullet, their ranges declared once
    (:func:`prg.fields.ranged`): :class:`SimSettings` (``conf/simulate.yaml``'s defaults,
    :meth:`SimSettings.from_mapping`), :class:`Paper`, :class:`MotionSettings`,
    :class:`ControlSettings`, :class:`IKSettings`, :class:`Camera` and :class:`RobotSettings`
    (``conf/robot/*.yaml``, :meth:`RobotSettings.named`); ``prg-simulate`` checks its config
    against them before loading the simulator.
:mod:`prg.sim.writing`
    :func:`simulate_word`: place, check the workspace, plan and solve the IK, write, render.
:mod:`prg.sim.ink`
    The ink as PNG, SVG and the paper's texture.
:mod:`prg.recording.simulation`
    The Rerun recording (URDF arm animated over ``sim_time``, pen path, ink, command).
:mod:`prg.sim.font`
    Words from a Hershey font, without a model (tests, benchmark, a first try).

The names below are imported from their modules on first use (``from prg.sim import
SimSettings`` loads neither numpy nor PyBullet), so that importing the package, as importing
:mod:`prg.sim.settings` does, stays light.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from prg.sim.font import font_word
    from prg.sim.geometry import (
        distance_to_polylines,
        in_contact,
        max_ink_gap,
        pen_down_samples,
        tracking_error,
    )
    from prg.sim.ik import IKSolver, UnreachableError
    from prg.sim.ink import ink_png, ink_svg
    from prg.sim.plan import MotionPlan, plan_motion
    from prg.sim.scene import Scene
    from prg.sim.settings import (
        Camera,
        ControlSettings,
        IKSettings,
        MotionSettings,
        Paper,
        RobotSettings,
        SimSettings,
    )
    from prg.sim.workspace import ReachMap, check_workspace
    from prg.sim.writing import SimResult, simulate_word, word_samples

_MODULES = {  # each exported name -> the module that defines it (imported on first use)
    "font_word": "font",
    "Paper": "settings",
    "distance_to_polylines": "geometry",
    "in_contact": "geometry",
    "max_ink_gap": "geometry",
    "pen_down_samples": "geometry",
    "tracking_error": "geometry",
    "IKSettings": "settings",
    "IKSolver": "ik",
    "UnreachableError": "ik",
    "ink_png": "ink",
    "ink_svg": "ink",
    "MotionPlan": "plan",
    "MotionSettings": "settings",
    "plan_motion": "plan",
    "RobotSettings": "settings",
    "Camera": "settings",
    "Scene": "scene",
    "ControlSettings": "settings",
    "SimSettings": "settings",
    "ReachMap": "workspace",
    "check_workspace": "workspace",
    "SimResult": "writing",
    "simulate_word": "writing",
    "word_samples": "writing",
}

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
