"""Robot descriptions as data: which URDF, which joints, where the pen is, where the base stands.

A :class:`RobotSettings` is read from ``conf/robot/<name>.yaml`` (:meth:`RobotSettings.named`) or
built from such a node (:meth:`RobotSettings.from_dict`) and holds nothing but plain values;
:func:`prg.sim.bullet.load_robot` loads it into a PyBullet client and resolves the joint and link
names to indices there (:class:`LoadedRobot`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from prg.errors import DataFormatError, SettingsError, UsageError
from prg.fields import FromMapping, as_float, check, positive, vector
from prg.resources import config_dir

__all__ = ["LoadedRobot", "RobotSettings", "pybullet_data_path", "resolve_urdf"]


def pybullet_data_path() -> Path:
    """The ``pybullet_data`` folder (URDFs of the Panda, the iiwa, the table ...)."""
    import pybullet_data

    return Path(pybullet_data.getDataPath())


def resolve_urdf(path: str | os.PathLike) -> Path:
    """An absolute URDF path: ``path`` itself if absolute, else relative to ``pybullet_data``.

    Raises
    ------
    UsageError
        If the file does not exist or is not a URDF (XML whose root is ``<robot>``).
    """
    candidate = Path(path)
    full = candidate if candidate.is_absolute() else pybullet_data_path() / candidate
    if not full.is_file():
        raise UsageError(f"robot.urdf {path}: no such URDF (relative paths are in pybullet_data)")
    import xml.etree.ElementTree as ET

    try:
        root = ET.parse(full).getroot()
    except (ET.ParseError, UnicodeDecodeError, OSError) as err:
        raise UsageError(f"robot.urdf {full}: not a URDF file (not XML: {err})") from None
    if root.tag != "robot":
        raise UsageError(
            f"robot.urdf {full}: not a URDF file (its root is <{root.tag}>, not <robot>)"
        )
    return full


_REQUIRED = ("name", "urdf", "flange_link", "arm_joints", "rest_pose", "pen_offset")


@dataclass(frozen=True)
class RobotSettings(FromMapping):
    """A 7-DOF arm holding a pen.

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
    rest_pose: tuple[float, ...]
    pen_offset: tuple[float, float, float]
    held_joints: Mapping[str, float] = field(default_factory=dict)
    pen_length: float = 0.12
    pen_radius: float = 0.005
    base_position: tuple[float, float, float] = (0.0, 0.0, 0.625)
    base_yaw_deg: float = 0.0

    def __post_init__(self) -> None:
        for name in ("name", "urdf", "flange_link"):
            object.__setattr__(self, name, str(getattr(self, name)))
        check(
            isinstance(self.arm_joints, Sequence) and not isinstance(self.arm_joints, str),
            "arm_joints",
            f"must be a list of joint names, got {self.arm_joints!r}",
        )
        arm = tuple(str(j) for j in self.arm_joints)
        held = {} if self.held_joints is None else self.held_joints
        check(
            isinstance(held, Mapping),
            "held_joints",
            f"must map joint names to values, got {held!r}",
        )
        n = len(arm)
        rest = vector(
            self.rest_pose, "rest_pose", n, f"must be {n} numbers (rad), one per arm joint"
        )
        offset = vector(self.pen_offset, "pen_offset", 3, "must be 3 finite numbers")
        check(np.linalg.norm(offset) > 0, "pen_offset", "must not be zero")
        base = vector(self.base_position, "base_position", 3, "must be 3 finite numbers")
        positive(self, "pen_length", "pen_radius", what="a positive number (m)")
        yaw = as_float(self.base_yaw_deg, "base_yaw_deg")
        check(math.isfinite(yaw), "base_yaw_deg", f"must be a finite number, got {yaw!r}")
        for name, value in (
            ("arm_joints", arm),
            ("rest_pose", rest),
            ("pen_offset", offset),
            ("base_position", base),
            ("base_yaw_deg", yaw),
            ("pen_length", float(self.pen_length)),
            ("pen_radius", float(self.pen_radius)),
            ("held_joints", {str(k): as_float(v, f"held_joints.{k}") for k, v in held.items()}),
        ):
            object.__setattr__(self, name, value)

    @classmethod
    def from_dict(cls, node: Mapping[str, Any]) -> RobotSettings:
        """From a ``conf/robot/*.yaml`` node (a mapping of the fields; ``name``, ``urdf``,
        ``flange_link``, ``arm_joints``, ``rest_pose`` and ``pen_offset`` are required).

        Raises
        ------
        SettingsError
            Naming the field that is missing, unknown or refused (``pen_offset must be 3 finite
            numbers, got ...``); the caller adds the config path (``.under("robot")``).
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
        """The URDF as an absolute path (:func:`resolve_urdf`)."""
        return resolve_urdf(self.urdf)

    @property
    def base_quaternion(self) -> tuple[float, float, float, float]:
        """Base orientation (x, y, z, w): a rotation of ``base_yaw_deg`` about z."""
        half = math.radians(self.base_yaw_deg) / 2
        return (0.0, 0.0, math.sin(half), math.cos(half))


@dataclass(frozen=True)
class LoadedRobot:
    """A :class:`RobotSettings` loaded into one PyBullet client: body and indices.

    Attributes
    ----------
    config : RobotSettings
    body : int
        PyBullet body unique id.
    flange : int
        Link index of ``config.flange_link``.
    arm : tuple of int
        Joint indices of ``config.arm_joints``.
    movable : tuple of int
        Every non-fixed joint, in index order (what PyBullet's IK returns, one value each).
    arm_in_movable : tuple of int
        Position of each arm joint in ``movable``.
    lower, upper, max_force : ndarray, shape (len(movable),)
        Joint limits and motor forces from the URDF.
    held : dict of int to float
        Joint index to value for ``config.held_joints``.
    """

    config: RobotSettings
    body: int
    flange: int
    arm: tuple[int, ...]
    movable: tuple[int, ...]
    arm_in_movable: tuple[int, ...]
    lower: np.ndarray
    upper: np.ndarray
    max_force: np.ndarray
    held: dict[int, float]

    @property
    def rest_movable(self) -> np.ndarray:
        """The rest pose over all movable joints (held joints at their values), shape (m,)."""
        q = np.zeros(len(self.movable))
        for i, value in zip(self.arm_in_movable, self.config.rest_pose):
            q[i] = value
        for joint, value in self.held.items():
            q[self.movable.index(joint)] = value
        return q
