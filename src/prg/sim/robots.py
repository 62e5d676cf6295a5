"""Robot descriptions as data: which URDF, which joints, where the pen is, where the base stands.

A :class:`RobotSettings` is read from ``conf/robot/<name>.yaml`` (:meth:`RobotSettings.named`) or
built from such a node (:meth:`RobotSettings.from_dict`) and holds nothing but plain values;
:func:`prg.sim.bullet.load_robot` loads it into a PyBullet client and resolves the joint and link
names to indices there (:class:`LoadedRobot`).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from prg.errors import UsageError
from prg.sim.settings import RobotSettings  # re-exported

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
