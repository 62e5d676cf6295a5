"""A simulated arm's writing as files a real arm's software reads: ROS 2 MCAP and CSV.

:func:`robot_trajectory` takes a :class:`~prg.sim.writing.SimResult` and returns the
**commanded** joint trajectory (the IK solution of every waypoint of the motion plan, at the
plan's times: what a trajectory controller is sent, not the simulated arm's response), with the
pen tip's pose at each waypoint in the **robot base frame** (forward kinematics of those joints;
metres, quaternions ``x, y, z, w``; the frame of the URDF's base link, e.g. ``panda_link0``).
Before anything is returned it is checked (:mod:`prg.export.limits`): joint positions, velocity,
acceleration and jerk against the arm's limits — the tighter of the URDF's (read through
PyBullet) and a datasheet's — with the whole timing slowed uniformly when that makes it fit, and
the pen's height over the paper.

Files: :func:`write_mcap` (``trajectory_msgs/msg/JointTrajectory`` on ``/joint_trajectory`` and
``nav_msgs/msg/Path`` on ``/pen_path``, one message each, plus a metadata record ``prg.export``)
and :func:`write_csv` (one row per waypoint: time, joint angles, pen-tip pose, pen down).
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from prg.errors import UsageError
from prg.export.limits import (
    ContactCheck,
    JointLimits,
    LimitSettings,
    TimingCheck,
    check_contact,
    check_timing,
)
from prg.export.ros import (
    JOINT_TRAJECTORY,
    PATH,
    joint_trajectory_message,
    msgdef,
    path_message,
)
from prg.files import atomic_path, json_text

if TYPE_CHECKING:
    from prg.sim import Paper, RobotSettings, SimResult

log = logging.getLogger(__name__)

__all__ = [
    "ArmModel",
    "RobotTrajectory",
    "robot_trajectory",
    "write_csv",
    "write_mcap",
]

JOINT_TOPIC = "/joint_trajectory"
PATH_TOPIC = "/pen_path"


class ArmModel:
    """The arm's URDF in a PyBullet client of its own (DIRECT): its limits, base link and base
    pose, and the pen tip's pose for given joint positions. Close it (or use ``with``)."""

    def __init__(self, robot: RobotSettings) -> None:
        from prg.sim.bullet import load_robot, pybullet

        self.p = p = pybullet()
        self.cid = p.connect(p.DIRECT)
        try:
            self.robot = load_robot(p, self.cid, robot)
        except BaseException:
            self.close()
            raise
        self.base_link = p.getBodyInfo(self.robot.body, physicsClientId=self.cid)[0].decode()
        # the base link's frame where the arm was loaded (PyBullet's getBasePositionAndOrientation
        # gives the base's centre of mass instead)
        position, orientation = robot.base_position, robot.base_quaternion
        self.base_position = np.asarray(position, dtype=np.float64)
        self.base_rotation = np.asarray(
            p.getMatrixFromQuaternion(orientation, physicsClientId=self.cid)
        ).reshape(3, 3)
        self.base_quaternion = np.asarray(orientation, dtype=np.float64)

    def urdf_limits(self) -> JointLimits:
        """The arm joints' position and velocity limits as the URDF gives them."""
        p, r = self.p, self.robot
        infos = [p.getJointInfo(r.body, j, physicsClientId=self.cid) for j in r.arm]
        velocity = np.array([info[11] for info in infos])
        return JointLimits(
            names=r.config.arm_joints,
            lower=np.array([info[8] for info in infos]),
            upper=np.array([info[9] for info in infos]),
            velocity=velocity if np.all(velocity > 0) else None,
            source=f"URDF {r.config.urdf}",
        )

    def arm_columns(self, q_movable: NDArray[np.float64]) -> NDArray[np.float64]:
        """The arm joints' columns of positions over all movable joints (as the IK solves)."""
        return np.asarray(q_movable)[:, list(self.robot.arm_in_movable)]

    def tip_poses(
        self, q_movable: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The pen tip's world position (m) and the pen's orientation (x, y, z, w) for each row of
        ``q_movable`` (n, len(movable))."""
        from prg.sim.bullet import pen_tip

        p, r = self.p, self.robot
        positions = np.empty((len(q_movable), 3))
        orientations = np.empty((len(q_movable), 4))
        for i, row in enumerate(np.asarray(q_movable, dtype=np.float64)):
            for joint, value in zip(r.movable, row):
                p.resetJointState(r.body, joint, float(value), 0.0, physicsClientId=self.cid)
            positions[i], orientations[i] = pen_tip(p, self.cid, r)
        return positions, orientations

    def to_base(
        self, positions: NDArray[np.float64], quaternions: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """World positions (n, 3) and orientations (n, 4) in the base link's frame."""
        local = (np.asarray(positions) - self.base_position) @ self.base_rotation
        inverse = self.p.invertTransform([0, 0, 0], self.base_quaternion.tolist())[1]
        quats = np.array(
            [
                self.p.multiplyTransforms([0, 0, 0], inverse, [0, 0, 0], list(q))[1]
                for q in np.asarray(quaternions)
            ]
        )
        return local, _canonical(quats)

    def close(self) -> None:
        if getattr(self, "cid", None) is not None and self.cid >= 0:
            self.p.disconnect(physicsClientId=self.cid)
        self.cid = None

    def __enter__(self) -> ArmModel:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def _canonical(quaternions: NDArray[np.float64]) -> NDArray[np.float64]:
    """Unit quaternions without sign jumps: q and -q are one rotation, and the pen held upside
    down is a half turn (``w`` near 0), where PyBullet's sign flips from one pose to the next;
    each is given the sign nearer its predecessor (the first: ``w >= 0``), so the path's
    orientation is continuous for readers that interpolate it."""
    q = quaternions / np.linalg.norm(quaternions, axis=1, keepdims=True)
    if len(q) and q[0, 3] < 0:
        q[0] = -q[0]
    for i in range(1, len(q)):
        if np.dot(q[i], q[i - 1]) < 0:
            q[i] = -q[i]
    return q


@dataclass(frozen=True)
class RobotTrajectory:
    """A checked joint trajectory and the pen tip's path, ready to send.

    Attributes
    ----------
    text : str
    robot : str
    base_link : str
        The frame of ``tip_position``/``tip_orientation`` (the URDF's base link).
    joint_names : tuple of str
    t : ndarray, shape (n,)
        Seconds from the start, **after** the slow-down (``timing.slow_down``).
    q : ndarray, shape (n, J)
        Joint positions (rad).
    qd : ndarray, shape (n, J)
        Joint velocities (rad/s): the divided difference over the two neighbouring waypoints,
        zero at the first and last (the arm starts and ends at rest).
    tip_position : ndarray, shape (n, 3)
        Pen tip (m), base frame.
    tip_orientation : ndarray, shape (n, 4)
        Pen (flange) orientation ``(x, y, z, w)``, base frame, without sign jumps from one
        waypoint to the next.
    pen_down : ndarray of bool, shape (n,)
        The waypoints that write.
    timing : TimingCheck
    contact : ContactCheck
    limits : JointLimits
        The limits checked against.
    """

    text: str
    robot: str
    base_link: str
    joint_names: tuple[str, ...]
    t: NDArray[np.float64]
    q: NDArray[np.float64]
    qd: NDArray[np.float64]
    tip_position: NDArray[np.float64]
    tip_orientation: NDArray[np.float64]
    pen_down: NDArray[np.bool_]
    timing: TimingCheck
    contact: ContactCheck
    limits: JointLimits

    @property
    def slow_down(self) -> float:
        return self.timing.slow_down

    @property
    def duration_s(self) -> float:
        return float(self.t[-1] - self.t[0])

    @property
    def pen_down_s(self) -> float:
        """Time spent between consecutive pen-down waypoints (s), as sent."""
        both = self.pen_down[1:] & self.pen_down[:-1]
        return float(np.diff(self.t)[both].sum())

    def metadata(self) -> dict[str, Any]:
        """What the MCAP's metadata record and ``export.json`` say about it."""
        return {
            "text": self.text,
            "robot": self.robot,
            "base_link": self.base_link,
            "joints": list(self.joint_names),
            "waypoints": len(self.t),
            "duration_s": self.duration_s,
            "pen_down_s": self.pen_down_s,
            "timing": self.timing.as_dict(),
            "contact": self.contact.as_dict(),
            "limits_source": self.limits.source,
        }


def _velocities(t: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
    qd = np.zeros_like(q)
    qd[1:-1] = (q[2:] - q[:-2]) / (t[2:] - t[:-2])[:, None]
    return qd


def robot_trajectory(
    result: SimResult,
    datasheet: JointLimits | None = None,
    settings: LimitSettings | None = None,
    paper: Paper | None = None,
) -> RobotTrajectory:
    """The commanded joint trajectory of a simulated writing, checked and (if need be) slowed.

    Parameters
    ----------
    result : SimResult
        From :func:`prg.sim.simulate_word`: its motion plan (``plan.t``, ``plan.pen_down``) and
        the IK solution of every waypoint (``q_plan``).
    datasheet : JointLimits, optional
        Limits beyond the URDF's (velocity, acceleration, jerk, tighter positions); the tighter
        of the two is checked.
    settings : LimitSettings, optional
    paper : Paper, optional
        The paper as it lies at the real arm, if it differs from the simulated one; the pen's
        height is measured from its surface. Default: ``result.settings.paper``.

    Returns
    -------
    RobotTrajectory

    Raises
    ------
    UsageError
        The trajectory leaves the joint limits, needs more slow-down than allowed, or the pen
        would not touch the paper (or press too far into it) — one line, nothing returned.
    """
    settings = settings or LimitSettings()
    paper = paper or result.settings.paper
    band = result.settings.control.contact_band_mm
    above = band if settings.contact_above_mm is None else settings.contact_above_mm
    compliance = band if settings.compliance_mm is None else settings.compliance_mm
    plan = result.plan
    with ArmModel(result.robot) as arm:
        limits = arm.urdf_limits().tighter(datasheet)
        q = arm.arm_columns(result.q_plan)
        timing = check_timing(plan.t, q, limits, settings.max_slow_down)
        world, orientation = arm.tip_poses(result.q_plan)
        heights_mm = paper.to_paper(world)[:, 2] * 10.0
        contact = check_contact(heights_mm, plan.pen_down, plan.t, above, compliance)
        position, quaternion = arm.to_base(world, orientation)
        base_link = arm.base_link
    t = (plan.t - plan.t[0]) * timing.slow_down
    if timing.slow_down > 1.0:
        log.warning("%s writing %r: %s", result.robot.name, result.text, timing.describe())
    else:
        log.info("%s writing %r: %s", result.robot.name, result.text, timing.describe())
    return RobotTrajectory(
        text=result.text,
        robot=result.robot.name,
        base_link=base_link,
        joint_names=limits.names,
        t=t,
        q=q,
        qd=_velocities(t, q),
        tip_position=position,
        tip_orientation=quaternion,
        pen_down=np.asarray(plan.pen_down, dtype=bool),
        timing=timing,
        contact=contact,
        limits=limits,
    )


# ----------------------------------------------------------------------------- files


def _metadata_strings(metadata: dict[str, Any]) -> dict[str, str]:
    """MCAP metadata values are strings: numbers and nested values as JSON text."""
    return {
        key: value if isinstance(value, str) else json_text(value).strip()
        for key, value in metadata.items()
    }


def write_mcap(trajectory: RobotTrajectory, path: str | os.PathLike) -> Path:
    """Write the trajectory as an MCAP file (ROS 2 profile), atomically; returns the path.

    Topics: ``/joint_trajectory`` (one ``trajectory_msgs/msg/JointTrajectory``: every waypoint
    with positions, velocities and ``time_from_start``; header stamp zero, frame the base link)
    and ``/pen_path`` (one ``nav_msgs/msg/Path``: the pen tip's pose at every waypoint in the
    base link's frame, each stamped with its time from the start). Both are logged at time 0, so
    the file's bytes depend on the trajectory alone. A metadata record ``prg.export`` holds
    :meth:`RobotTrajectory.metadata` (JSON text per key).
    """
    from mcap_ros2.writer import Writer

    path = Path(path)
    tr = trajectory
    with atomic_path(path) as tmp, tmp.open("wb") as stream:
        writer = Writer(stream)
        joint_schema = writer.register_msgdef(JOINT_TRAJECTORY, msgdef(JOINT_TRAJECTORY))
        path_schema = writer.register_msgdef(PATH, msgdef(PATH))
        writer.write_message(
            JOINT_TOPIC,
            joint_schema,
            joint_trajectory_message(tr.base_link, list(tr.joint_names), tr.t, tr.q, tr.qd),
            log_time=0,
        )
        writer.write_message(
            PATH_TOPIC,
            path_schema,
            path_message(tr.base_link, tr.t, tr.tip_position, tr.tip_orientation),
            log_time=0,
        )
        writer.add_metadata("prg.export", _metadata_strings(tr.metadata()))
        writer.finish()
    return path


CSV_POSE = ("x_m", "y_m", "z_m", "qx", "qy", "qz", "qw")


def write_csv(trajectory: RobotTrajectory, path: str | os.PathLike) -> Path:
    """Write one row per waypoint, atomically: ``t_s``, the joint angles (rad, one column per
    joint, named), the pen tip's pose in the base frame (``x_m, y_m, z_m, qx, qy, qz, qw``) and
    ``pen_down`` (0/1). Returns the path."""
    tr = trajectory
    columns = np.column_stack(
        [tr.t, tr.q, tr.tip_position, tr.tip_orientation, tr.pen_down.astype(np.float64)]
    )
    header = ",".join(["t_s", *tr.joint_names, *CSV_POSE, "pen_down"])
    fmt = ["%.9f"] * (1 + len(tr.joint_names) + len(CSV_POSE)) + ["%d"]
    if not len(columns):
        raise UsageError("the trajectory has no waypoints")
    with atomic_path(Path(path)) as tmp:
        np.savetxt(tmp, columns, delimiter=",", header=header, comments="", fmt=fmt)
    return Path(path)
