"""The simulation's settings, each range declared once: the paper, the pen's moves, the control,
the IK, the camera, the robot, and the word's placement and tempo.

:class:`SimSettings` gathers :class:`Paper`, :class:`MotionSettings`, :class:`ControlSettings`,
:class:`IKSettings`, :class:`Camera` and the word's placement and tempo; :class:`RobotSettings`
describes the arm (``conf/robot/<name>.yaml``). ``SimSettings()`` holds the defaults of
``conf/simulate.yaml``; :meth:`SimSettings.from_mapping` builds it from a plain nested mapping
shaped like that config (what ``prg-simulate`` reads).

Each numeric field declares the values it accepts (:func:`prg.fields.ranged`): the dataclass
checks them (:func:`prg.fields.check_fields`) and :data:`prg.checks.RANGES` takes its
``paper.*``, ``motion.*``, ``control.*``, ``ik.*``, ``camera.*`` and ``robot.*`` entries from
them (:data:`prg.checks.DECLARED`), so ``prg-simulate motion.lift_cm=0`` and
``MotionSettings(lift_cm=0)`` refuse the same value with the same line (the command adds the
node: ``motion.lift_cm must be a finite number in (0, 100], got 0``). The word's placement and
tempo are top-level keys of the config (``scale``, ``tempo``, ``workspace_step_cm``) or under
``paper`` (``paper.word_centre_cm``), so their ranges stay named constants of
:mod:`prg.checks` (:data:`~prg.checks.SCALE` ...) that :class:`SimSettings` declares its fields
with.

This module imports neither numpy nor PyBullet (the few methods that compute import numpy when
called), so that ``prg-simulate`` checks its config before loading them;
:mod:`prg.sim.geometry`, :mod:`prg.sim.plan`, :mod:`prg.sim.ik`, :mod:`prg.sim.scene` and
:mod:`prg.sim.robots` export these classes too.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import MISSING, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from prg.checks import (
    DEGREES,
    METRES,
    SCALE,
    TEMPO,
    WORD_CENTRE_CM,
    WORKSPACE_STEP_CM,
    Range,
    count,
    non_negative,
    positive,
)
from prg.errors import DataFormatError, SettingsError, UsageError
from prg.fields import FromMapping, check, check_fields, listed_as_tuple, ranged

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import ArrayLike, NDArray

__all__ = [
    "IK_METHODS",
    "Camera",
    "ControlSettings",
    "IKSettings",
    "MotionSettings",
    "Paper",
    "RobotSettings",
    "SimSettings",
]

IK_METHODS = ("refined", "null_space", "plain")
DURATION_S = positive(60)  # a move of the pen (s)
ITERATIONS = count(1, 100_000)  # of an IK solve
PIXELS = count(16, 8192)  # a side of the page render


def _floats(settings: Any, *names: str) -> None:
    """Store the (checked) numbers ``names`` of a frozen dataclass as ``float``."""
    for name in names:
        object.__setattr__(settings, name, float(getattr(settings, name)))


@dataclass(frozen=True)
class Paper(FromMapping):
    """A sheet on the table: size and pose (the defaults are ``conf/simulate.yaml``'s).

    Attributes
    ----------
    size_cm : tuple of float
        Width (along the paper's x, the writing line) and height, in cm (A3 landscape).
    centre : tuple of float
        Centre of the top surface in the world (m).
    yaw_deg : float
        Heading of the paper's x axis in the world (degrees about z; ``-90``: x along world
        ``-y``, so a robot at the origin facing ``+x`` writes left to right as it sees it).
    thickness_m : float
        Thickness of the sheet (m); it lies on the table, its top surface at ``centre[2]``.
    """

    size_cm: tuple[float, float] = ranged((42.0, 29.7), positive(1000), items=2)
    centre: tuple[float, float, float] = ranged((0.55, 0.0, 0.6255), METRES, items=3)
    yaw_deg: float = ranged(-90.0, DEGREES)
    thickness_m: float = ranged(0.0005, positive(0.1))

    def __post_init__(self) -> None:
        check_fields(self)
        _floats(self, "yaw_deg", "thickness_m")

    @property
    def rotation(self) -> NDArray[np.float64]:
        """World-from-paper rotation, shape (3, 3): columns are the paper's axes in the world."""
        import numpy as np

        c, s = math.cos(math.radians(self.yaw_deg)), math.sin(math.radians(self.yaw_deg))
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])

    @property
    def quaternion(self) -> tuple[float, float, float, float]:
        """World-from-paper orientation (x, y, z, w)."""
        half = math.radians(self.yaw_deg) / 2
        return (0.0, 0.0, math.sin(half), math.cos(half))

    def to_world(self, points_cm: ArrayLike) -> NDArray[np.float64]:
        """Paper-frame points (cm) to world points (m).

        Parameters
        ----------
        points_cm : array_like, shape (n, 2) or (n, 3)
            ``(x, y)`` on the paper or ``(x, y, height)`` above it, in cm.

        Returns
        -------
        ndarray, shape (n, 3)
        """
        import numpy as np

        pts = np.asarray(points_cm, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] not in (2, 3):
            raise UsageError(f"points must have shape (n, 2) or (n, 3), got {pts.shape}")
        if pts.shape[1] == 2:
            pts = np.column_stack([pts, np.zeros(len(pts))])
        return pts / 100.0 @ self.rotation.T + np.asarray(self.centre)

    def to_paper(self, points_m: ArrayLike) -> NDArray[np.float64]:
        """World points (m) to paper-frame ``(x, y, height)`` in cm, shape (n, 3)."""
        import numpy as np

        pts = np.asarray(points_m, dtype=np.float64).reshape(-1, 3)
        return (pts - np.asarray(self.centre)) @ self.rotation * 100.0

    def contains(self, points_cm: ArrayLike, margin_cm: float = 0.0) -> NDArray[np.bool_]:
        """Whether each ``(x, y)`` lies on the sheet, at least ``margin_cm`` from its edges."""
        import numpy as np

        pts = np.asarray(points_cm, dtype=np.float64)[:, :2]
        half = np.asarray(self.size_cm) / 2 - margin_cm
        return np.all(np.abs(pts) <= half, axis=1)


@dataclass(frozen=True)
class MotionSettings(FromMapping):
    """Durations and heights of the pen's moves around the writing (:mod:`prg.sim.plan`).

    Attributes
    ----------
    lift_cm : float
        Height of the pen tip above the paper when it is up (approach, travel between words).
    approach_s : float
        Duration of the approach from home and of the retreat back.
    lower_s, lift_s : float
        Duration of lowering the pen onto the paper and lifting it off.
    dwell_s : float
        Time the pen rests on the paper before a stroke starts.
    """

    lift_cm: float = ranged(1.5, positive(100))
    approach_s: float = ranged(2.0, DURATION_S)
    lower_s: float = ranged(0.6, DURATION_S)
    lift_s: float = ranged(0.6, DURATION_S)
    dwell_s: float = ranged(0.2, non_negative(60))

    def __post_init__(self) -> None:
        check_fields(self)


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

    time_step: float = ranged(1.0 / 240.0, positive(0.05))
    steps_per_waypoint: int = ranged(4, count(1, 1000))
    position_gain: float = ranged(0.5, positive(100))
    velocity_gain: float = ranged(1.0, positive(100))
    contact_band_mm: float = ranged(0.5, positive(100))
    settle_s: float = ranged(0.25, non_negative(60))

    def __post_init__(self) -> None:
        check_fields(self)

    @property
    def waypoint_dt(self) -> float:
        """Time between IK waypoints (s)."""
        return self.time_step * self.steps_per_waypoint


@dataclass(frozen=True)
class IKSettings(FromMapping):
    """Inverse kinematics (:class:`prg.sim.ik.IKSolver`): null-space IK for posture, refined by a
    plain IK solve seeded from it.

    Attributes
    ----------
    null_space_iterations : int
        Iterations of the null-space solve (rest pose, joint limits and ranges) when seeded
        with the previous waypoint's solution.
    refine_iterations : int
        Iterations of the plain (damped least squares) refinement seeded from it.
    cold_iterations : int
        Iterations of both solves when starting from the rest pose (the first waypoint, the
        workspace map's nodes): far targets need more.
    residual : float
        Residual threshold of both solves (m).
    tolerance_mm : float
        Largest pen-tip error of a solution (mm); above it, or outside the joint limits, the
        target is unreachable.
    method : str
        ``"refined"``: the null-space solve, then the plain solve seeded from it (default);
        ``"null_space"``: the null-space solve alone; ``"plain"``: the plain solve alone, seeded
        with the previous solution (no rest pose, no limits). The last two are the references
        ``benchmarks/bench_simulate.py`` compares with.
    """

    null_space_iterations: int = ranged(20, ITERATIONS)
    refine_iterations: int = ranged(100, ITERATIONS)
    cold_iterations: int = ranged(100, ITERATIONS)
    residual: float = ranged(1e-7, positive(1))
    tolerance_mm: float = ranged(0.5, positive(1000))
    method: str = "refined"

    def __post_init__(self) -> None:
        check(
            self.method in IK_METHODS, "method", f"{self.method!r}: choose {', '.join(IK_METHODS)}"
        )
        check_fields(self)


@dataclass(frozen=True)
class Camera(FromMapping):
    """A TinyRenderer camera looking down at the paper (:mod:`prg.sim.scene`).

    The default looks straight down at the word, the page upright in the picture (its top edge,
    away from the robot, at the top), from as close as frames the word with a margin.

    Attributes
    ----------
    width, height : int
        Image size (pixels).
    distance : float or None
        From the target (m); None: frame the word (:meth:`framing_distance`). 0.5 shows the
        whole default sheet.
    yaw, pitch : float
        Degrees (PyBullet's ``computeViewMatrixFromYawPitchRoll`` convention).
    fov : float
        Vertical field of view (degrees).
    """

    width: int = ranged(1024, PIXELS)
    height: int = ranged(768, PIXELS)
    distance: float | None = ranged(None, Range(0, 100, low_open=True, optional=True))
    yaw: float = ranged(-90.0, DEGREES)
    pitch: float = ranged(-89.0, DEGREES)
    fov: float = ranged(45.0, Range(1, 170))

    def __post_init__(self) -> None:
        check_fields(self)

    def framing_distance(
        self, extent_m: ArrayLike, margin: float = 1.4, least: float = 0.08
    ) -> float:
        """Distance at which a region ``extent_m`` = (width, height) fills the picture, times
        ``margin``, and at least ``least`` m wide."""
        import numpy as np

        half_v = math.radians(self.fov) / 2
        half_h = math.atan(math.tan(half_v) * self.width / self.height)
        w, h = np.maximum(np.asarray(extent_m, dtype=np.float64) * margin, least) / 2
        return float(max(w / math.tan(half_h), h / math.tan(half_v)))


_REQUIRED = ("name", "urdf", "flange_link", "arm_joints", "rest_pose", "pen_offset")


@dataclass(frozen=True)
class RobotSettings(FromMapping):
    """A 7-DOF arm holding a pen (:mod:`prg.sim.robots`).

    Attributes
    ----------
    name : str
        Short name (``panda``, ``iiwa``).
    urdf : str
        URDF file, absolute or relative to ``pybullet_data``.
    flange_link : str
        The link the pen is fixed to (the inverse kinematics' end effector).
    arm_joints : tuple of str
        The arm's revolute joints, base to flange (IK moves these).
    rest_pose : tuple of float
        Preferred arm posture (rad), one per arm joint: the null-space IK's rest pose and the
        posture before and after writing.
    held_joints : dict of str to float
        Other movable joints, held at these values (e.g. the Panda's fingers closed on the pen).
    pen_offset : tuple of float, length 3
        Pen tip in the flange frame (m). The pen points along this offset; it is held vertical,
        tip down, while writing.
    pen_length, pen_radius : float
        Size of the drawn pen (m), from the tip towards the flange.
    base_position : tuple of float, length 3
        Base in the world (m); the default stands it on the table top.
    base_yaw_deg : float
        Base heading (degrees about the world z axis).
    """

    name: str
    urdf: str
    flange_link: str
    arm_joints: tuple[str, ...]
    rest_pose: tuple[float, ...] = ranged(MISSING, METRES, items=True)  # rad (m: sliding)
    pen_offset: tuple[float, float, float] = ranged(MISSING, METRES, items=3)
    held_joints: Mapping[str, float] = ranged({}, METRES, keyed=True)
    pen_length: float = ranged(0.12, positive(10))
    pen_radius: float = ranged(0.005, positive(1))
    base_position: tuple[float, float, float] = ranged((0.0, 0.0, 0.625), METRES, items=3)
    base_yaw_deg: float = ranged(0.0, DEGREES)

    def __post_init__(self) -> None:
        for name in ("name", "urdf", "flange_link"):
            object.__setattr__(self, name, str(getattr(self, name)))
        check(
            isinstance(self.arm_joints, Sequence) and not isinstance(self.arm_joints, str),
            "arm_joints",
            f"must be a list of joint names, got {self.arm_joints!r}",
        )
        arm = tuple(str(j) for j in self.arm_joints)
        object.__setattr__(self, "arm_joints", arm)
        check_fields(self)
        n = len(arm)
        check(
            len(self.rest_pose) == n,
            "rest_pose",
            f"must be {n} numbers (rad), one per arm joint, got {self.rest_pose!r}",
        )
        check(any(self.pen_offset), "pen_offset", "must not be zero")
        _floats(self, "pen_length", "pen_radius", "base_yaw_deg")

    @classmethod
    def from_dict(cls, node: Mapping[str, Any]) -> RobotSettings:
        """From a ``conf/robot/*.yaml`` node (a mapping of the fields; ``name``, ``urdf``,
        ``flange_link``, ``arm_joints``, ``rest_pose`` and ``pen_offset`` are required).

        Raises
        ------
        SettingsError
            Naming the field that is missing, unknown or refused (``pen_offset must be 3
            numbers, each ...``); the caller adds the config path (``.under("robot")``).
        """
        if isinstance(node, Mapping):
            missing = [key for key in _REQUIRED if key not in node]
            if missing:
                raise SettingsError(missing[0], "is missing from the robot description")
        return cls.from_mapping(node)

    @classmethod
    def named(cls, name: str) -> RobotSettings:
        """The robot described by ``conf/robot/<name>.yaml`` (``panda``, ``iiwa``; the folder is
        :func:`prg.resources.config_dir`, ``PRG_CONF_DIR`` overrides it).

        Raises
        ------
        SettingsError
            For a name without a description (``robot 'kuka' is not a known robot: choose iiwa,
            panda``).
        DataFormatError
            For a description that cannot be read or is refused (naming the file and the field).
        """
        import yaml

        from prg.resources import config_dir

        folder = config_dir() / "robot"
        names = sorted(p.stem for p in folder.glob("*.yaml"))
        if name not in names:
            choose = f"choose {', '.join(names)}" if names else f"no robot descriptions in {folder}"
            raise SettingsError("robot", f"{name!r} is not a known robot: {choose}")
        path = folder / f"{name}.yaml"
        try:
            node = yaml.safe_load(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, yaml.YAMLError) as err:
            raise DataFormatError(
                f"not a robot description ({' '.join(str(err).split())})", path=str(path)
            ) from None
        try:
            return cls.from_dict(node)
        except UsageError as err:
            raise DataFormatError(str(err), path=str(path)) from None

    @property
    def urdf_path(self) -> Path:
        """The URDF as an absolute path (:func:`prg.sim.robots.resolve_urdf`)."""
        from prg.sim.robots import resolve_urdf

        return resolve_urdf(self.urdf)

    @property
    def base_quaternion(self) -> tuple[float, float, float, float]:
        """Base orientation (x, y, z, w): a rotation of ``base_yaw_deg`` about z."""
        half = math.radians(self.base_yaw_deg) / 2
        return (0.0, 0.0, math.sin(half), math.cos(half))


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

    ``SimSettings()`` is ``conf/simulate.yaml``'s defaults. Its own numbers are top-level keys
    of the config (``paper.word_centre_cm`` for the centre), declared with the ranges
    :data:`prg.checks.TABLE` keeps for those keys.

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
    scale: float = ranged(1.0, SCALE)
    word_centre_cm: tuple[float, float] = ranged((0.0, 0.0), WORD_CENTRE_CM, items=2)
    tempo: float = ranged(1.0, TEMPO)
    workspace_step_cm: float = ranged(1.0, WORKSPACE_STEP_CM)

    def __post_init__(self) -> None:
        for name, kind in _SECTIONS.items():
            value = getattr(self, name)
            check(
                isinstance(value, kind),
                name,
                f"must be a {kind.__name__}, got {type(value).__name__}",
            )
        check_fields(self)
        _floats(self, "scale", "tempo", "workspace_step_cm")

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
            Naming the value by its place in ``values`` (``motion.lift_cm must be a finite
            number in (0, 100], got 0``), including a key that is not a setting of its section.
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
