"""What the scene and the IK solver share of PyBullet: the module, loading the arm, the pen's pose.

Every call passes ``physicsClientId``; nothing uses PyBullet's default client, so several
clients (a :class:`~prg.sim.scene.Scene`, the :class:`~prg.sim.ik.IKSolver`'s kinematic copy of
the arm) live side by side.
"""

from __future__ import annotations

import os
import sys
from types import ModuleType

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prg.errors import PRGError, UsageError
from prg.sim.robots import LoadedRobot, RobotSettings

__all__ = ["flange_pose", "load_robot", "pen_tip", "pybullet", "rotate"]

Quaternion = tuple[float, float, float, float]


def pybullet() -> ModuleType:
    """The ``pybullet`` module, or a one-line error saying how to install it.

    Its import prints a build-time banner on the C level stderr; that is kept out, so that a
    command's stderr holds only what the command says."""
    if "pybullet" in sys.modules:
        return sys.modules["pybullet"]
    sys.stderr.flush()
    saved, devnull = os.dup(2), os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 2)
        import pybullet as p
    except ImportError:  # pragma: no cover - pybullet is a core dependency
        raise PRGError("the simulator needs pybullet: pip install pybullet") from None
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(devnull)
    return p


def rotate(quaternion: ArrayLike, vector: ArrayLike) -> NDArray[np.float64]:
    """Rotate ``vector`` (3,) by a unit quaternion (x, y, z, w)."""
    x, y, z, w = quaternion
    v = np.asarray(vector, dtype=np.float64)
    u = np.array([x, y, z])
    return v + 2.0 * np.cross(u, np.cross(u, v) + w * v)


def load_robot(p: ModuleType, cid: int, config: RobotSettings) -> LoadedRobot:
    """Load ``config``'s URDF into client ``cid`` (fixed base) and resolve its names to indices.

    Raises
    ------
    UsageError
        If PyBullet cannot load the URDF, or a joint or link named in ``config`` is missing (the
        message lists the ones there are), or an arm joint is fixed.
    """
    try:
        body = p.loadURDF(
            str(config.urdf_path),
            basePosition=config.base_position,
            baseOrientation=config.base_quaternion,
            useFixedBase=True,
            flags=p.URDF_USE_INERTIA_FROM_FILE,
            physicsClientId=cid,
        )
    except p.error as err:  # e.g. a link without geometry PyBullet accepts, a missing mesh
        raise UsageError(
            f"robot.urdf {config.urdf_path}: PyBullet cannot load it ({err})"
        ) from None
    joints: dict[str, int] = {}
    links: dict[str, int] = {}
    movable, lower, upper, force = [], [], [], []
    for j in range(p.getNumJoints(body, physicsClientId=cid)):
        info = p.getJointInfo(body, j, physicsClientId=cid)
        joints[info[1].decode()] = j
        links[info[12].decode()] = j
        if info[2] != p.JOINT_FIXED:
            movable.append(j)
            lower.append(info[8])
            upper.append(info[9])
            force.append(info[10])
    missing = [n for n in (*config.arm_joints, *config.held_joints) if n not in joints]
    if missing:
        raise UsageError(
            f"robot {config.name}: no joint {missing[0]!r} in {config.urdf} "
            f"(joints: {', '.join(joints)})"
        )
    if config.flange_link not in links:
        raise UsageError(
            f"robot {config.name}: no link {config.flange_link!r} in {config.urdf} "
            f"(links: {', '.join(links)})"
        )
    arm = tuple(joints[n] for n in config.arm_joints)
    not_movable = [n for n, j in zip(config.arm_joints, arm) if j not in movable]
    if not_movable:
        raise UsageError(f"robot {config.name}: arm joint {not_movable[0]!r} is fixed")
    return LoadedRobot(
        config=config,
        body=body,
        flange=links[config.flange_link],
        arm=arm,
        movable=tuple(movable),
        arm_in_movable=tuple(movable.index(j) for j in arm),
        lower=np.array(lower),
        upper=np.array(upper),
        max_force=np.array(force),
        held={joints[n]: v for n, v in config.held_joints.items()},
    )


def flange_pose(
    p: ModuleType, cid: int, robot: LoadedRobot
) -> tuple[NDArray[np.float64], Quaternion]:
    """The flange's position (m) and orientation (x, y, z, w) in the world, in the arm's current
    posture in client ``cid``."""
    state = p.getLinkState(
        robot.body, robot.flange, computeForwardKinematics=True, physicsClientId=cid
    )
    return np.asarray(state[4]), state[5]


def pen_tip(p: ModuleType, cid: int, robot: LoadedRobot) -> tuple[NDArray[np.float64], Quaternion]:
    """The pen tip's position (m) in the world and the pen's (the flange's) orientation."""
    position, orientation = flange_pose(p, cid, robot)
    return position + rotate(orientation, robot.config.pen_offset), orientation
