"""Robot descriptions as data: which URDF, which joints, where the pen is, where the base stands.

A :class:`RobotSettings` is built from a ``conf/robot/<name>.yaml`` node (:meth:`RobotSettings.from_dict`)
and holds nothing but plain values; :class:`prg.sim.scene.Scene` loads it into PyBullet and
resolves the joint and link names to indices there (:class:`LoadedRobot`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from prg.errors import UsageError

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


@dataclass(frozen=True)
class RobotSettings:
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
        if len(self.arm_joints) != len(self.rest_pose):
            raise UsageError(
                f"robot {self.name}: {len(self.arm_joints)} arm_joints but "
                f"{len(self.rest_pose)} rest_pose values"
            )
        for name, value, size in (
            ("pen_offset", self.pen_offset, 3),
            ("base_position", self.base_position, 3),
        ):
            arr = np.asarray(value, dtype=np.float64)
            if arr.shape != (size,) or not np.all(np.isfinite(arr)):
                raise UsageError(f"robot {self.name}: {name} must be {size} finite numbers")
        if np.linalg.norm(self.pen_offset) <= 0:
            raise UsageError(f"robot {self.name}: pen_offset must not be zero")
        for name in ("pen_length", "pen_radius"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise UsageError(f"robot {self.name}: {name} must be a positive number (m)")

    @classmethod
    def from_dict(cls, node: Mapping[str, Any]) -> RobotSettings:
        """From a ``conf/robot/*.yaml`` node (a mapping); names the bad key on error."""
        data = dict(node)
        try:
            return cls(
                name=str(data["name"]),
                urdf=str(data["urdf"]),
                flange_link=str(data["flange_link"]),
                arm_joints=tuple(str(j) for j in data["arm_joints"]),
                rest_pose=tuple(float(q) for q in data["rest_pose"]),
                pen_offset=tuple(float(v) for v in data["pen_offset"]),
                held_joints={str(k): float(v) for k, v in (data.get("held_joints") or {}).items()},
                pen_length=float(data.get("pen_length", 0.12)),
                pen_radius=float(data.get("pen_radius", 0.005)),
                base_position=tuple(float(v) for v in data.get("base_position", (0, 0, 0.625))),
                base_yaw_deg=float(data.get("base_yaw_deg", 0.0)),
            )
        except KeyError as err:
            raise UsageError(f"robot config: missing key {err.args[0]!r}") from None
        except (TypeError, ValueError) as err:
            raise UsageError(f"robot config: {err}") from None

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
