"""The simulation's settings: physics and control, and everything besides the word and the robot.

:class:`SimSettings` gathers the paper, the pen's moves, the control, the IK, the camera and the
word's placement and tempo. ``SimSettings()`` holds the defaults of ``conf/simulate.yaml``;
:meth:`SimSettings.from_mapping` builds it from a plain nested mapping shaped like that config
(what ``prg-simulate`` reads), and every dataclass checks its own values, so a bad one is one
:class:`~prg.errors.SettingsError` naming it by its place in the mapping (``motion.lift_cm must
be a positive number, got 0``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from prg.errors import SettingsError
from prg.fields import (
    FromMapping,
    as_float,
    at_least,
    check,
    listed_as_tuple,
    positive,
    positive_float,
    positive_integer,
    vector,
)
from prg.sim.geometry import Paper
from prg.sim.ik import IKSettings
from prg.sim.plan import MotionSettings
from prg.sim.scene import Camera

__all__ = ["ControlSettings", "SimSettings"]


@dataclass(frozen=True)
class ControlSettings(FromMapping):
    """Physics and position control.

    Attributes
    ----------
    time_step : float
        Physics step (s); PyBullet's default is 1/240.
    steps_per_waypoint : int
        Physics steps between IK waypoints; joint targets are interpolated linearly in between
        (with the matching velocity as feed-forward).
    position_gain, velocity_gain : float
        PyBullet ``POSITION_CONTROL`` gains (``kp``, ``kd`` of its velocity-level motor
        constraint), at the URDF's joint force limits.
    contact_band_mm : float
        The pen tip inks while within this distance of the paper surface.
    settle_s : float
        Simulated time after the retreat, holding the home posture.
    """

    time_step: float = 1.0 / 240.0
    steps_per_waypoint: int = 4
    position_gain: float = 0.5
    velocity_gain: float = 1.0
    contact_band_mm: float = 0.5
    settle_s: float = 0.25

    def __post_init__(self) -> None:
        step = as_float(self.time_step, "time_step")
        check(0 < step <= 0.05, "time_step", f"must be in (0, 0.05] s, got {self.time_step!r}")
        positive_integer(self, "steps_per_waypoint")
        positive(self, "position_gain", "velocity_gain", "contact_band_mm")
        at_least(self, "settle_s", 0.0)

    @property
    def waypoint_dt(self) -> float:
        """Time between IK waypoints (s)."""
        return self.time_step * self.steps_per_waypoint


# the nested settings of SimSettings: field (and key of from_mapping) -> class
_SECTIONS: dict[str, type[FromMapping]] = {
    "paper": Paper,
    "motion": MotionSettings,
    "control": ControlSettings,
    "ik": IKSettings,
    "camera": Camera,
}
_VALUES = ("scale", "word_centre_cm", "tempo", "workspace_step_cm")


@dataclass(frozen=True)
class SimSettings:
    """Everything :func:`~prg.sim.writing.simulate_word` needs besides the word and the robot.

    ``SimSettings()`` is ``conf/simulate.yaml``'s defaults.

    Attributes
    ----------
    paper : Paper
    motion : MotionSettings
    control : ControlSettings
    ik : IKSettings
    camera : Camera
        The page render.
    scale : float
        The word's size on the paper relative to its own (cm) size.
    word_centre_cm : tuple of float
        Where the centre of the word's bounding box goes, in the paper frame (cm).
    tempo : float
        Multiplies the DMP's duration (2: twice as slow).
    workspace_step_cm : float
        Grid spacing of the reachability map over the paper.
    """

    paper: Paper = field(default_factory=Paper)
    motion: MotionSettings = field(default_factory=MotionSettings)
    control: ControlSettings = field(default_factory=ControlSettings)
    ik: IKSettings = field(default_factory=IKSettings)
    camera: Camera = field(default_factory=Camera)
    scale: float = 1.0
    word_centre_cm: tuple[float, float] = (0.0, 0.0)
    tempo: float = 1.0
    workspace_step_cm: float = 1.0

    def __post_init__(self) -> None:
        for name, kind in _SECTIONS.items():
            value = getattr(self, name)
            check(
                isinstance(value, kind),
                name,
                f"must be a {kind.__name__}, got {type(value).__name__}",
            )
        for name in ("scale", "tempo", "workspace_step_cm"):
            value = positive_float(getattr(self, name), name, "a positive number")
            object.__setattr__(self, name, value)
        centre = vector(self.word_centre_cm, "word_centre_cm", 2, "must be two numbers")
        object.__setattr__(self, "word_centre_cm", centre)

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any] | None) -> SimSettings:
        """The settings from a plain nested mapping shaped like ``conf/simulate.yaml``.

        Parameters
        ----------
        values : mapping
            ``paper``, ``motion``, ``control``, ``ik``, ``camera`` (mappings of their fields),
            ``scale``, ``tempo``, ``workspace_step_cm`` and ``word_centre_cm`` (also accepted
            inside ``paper``, where the config has it). A missing key keeps its default; other
            top-level keys (the rest of a command's config) are not read.

        Raises
        ------
        SettingsError
            Naming the value by its place in ``values`` (``motion.lift_cm must be a positive
            number, got 0``), including a key that is not a setting of its section.
        """
        values = {} if values is None else values
        check(isinstance(values, Mapping), "settings", "must be a mapping")
        given = {k: listed_as_tuple(values[k]) for k in _VALUES if k in values}
        sections = {}
        centre_in_paper = False
        for name, kind in _SECTIONS.items():
            node = values.get(name)
            check(
                node is None or isinstance(node, Mapping),
                name,
                f"must be a mapping of settings, got {type(node).__name__}",
            )
            if name == "paper" and node is not None and "word_centre_cm" in node:
                node = dict(node)
                check(
                    "word_centre_cm" not in given,
                    "word_centre_cm",
                    "is given twice: as word_centre_cm and as paper.word_centre_cm",
                )
                given["word_centre_cm"] = listed_as_tuple(node.pop("word_centre_cm"))
                centre_in_paper = True
            try:
                sections[name] = kind.from_mapping(node)
            except SettingsError as err:
                raise err.under(name) from None
        try:
            return cls(**sections, **given)
        except SettingsError as err:
            if centre_in_paper and err.field == "word_centre_cm":
                raise err.under("paper") from None
            raise
