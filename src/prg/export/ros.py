"""ROS 2 message definitions and messages, for MCAP files readable without a ROS installation.

An MCAP file of the ``ros2`` profile carries each channel's schema as the message definition
text, the top-level ``.msg`` followed by every type it uses, each after a line of 80 ``=`` and
``MSG: package/Type`` (the concatenation ``ros2 bag`` writes). ``mcap-ros2-support`` encodes
plain dicts and lists against that text (CDR), so no ROS package is needed. The definitions below
are the field lists of the ROS 2 interfaces (``trajectory_msgs``, ``nav_msgs``,
``geometry_msgs``, ``std_msgs``, ``builtin_interfaces``; Humble and later), comments left out.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "JOINT_TRAJECTORY",
    "PATH",
    "duration",
    "joint_trajectory_message",
    "msgdef",
    "path_message",
]

_SEPARATOR = "=" * 80

# One entry per interface: its fields, as in its .msg file.
_FIELDS = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec",
    "builtin_interfaces/Duration": "int32 sec\nuint32 nanosec",
    "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id",
    "geometry_msgs/Point": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1",
    "geometry_msgs/Pose": "Point position\nQuaternion orientation",
    "geometry_msgs/PoseStamped": "std_msgs/Header header\nPose pose",
    "nav_msgs/Path": "std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses",
    "trajectory_msgs/JointTrajectoryPoint": (
        "float64[] positions\nfloat64[] velocities\nfloat64[] accelerations\nfloat64[] effort\n"
        "builtin_interfaces/Duration time_from_start"
    ),
    "trajectory_msgs/JointTrajectory": (
        "std_msgs/Header header\nstring[] joint_names\nJointTrajectoryPoint[] points"
    ),
}
# The types each one uses, depth first (the order the concatenated text lists them).
_USES = {
    "trajectory_msgs/JointTrajectory": (
        "std_msgs/Header",
        "builtin_interfaces/Time",
        "trajectory_msgs/JointTrajectoryPoint",
        "builtin_interfaces/Duration",
    ),
    "nav_msgs/Path": (
        "std_msgs/Header",
        "builtin_interfaces/Time",
        "geometry_msgs/PoseStamped",
        "geometry_msgs/Pose",
        "geometry_msgs/Point",
        "geometry_msgs/Quaternion",
    ),
}
JOINT_TRAJECTORY = "trajectory_msgs/msg/JointTrajectory"
PATH = "nav_msgs/msg/Path"


def msgdef(datatype: str) -> str:
    """The concatenated message definition of ``datatype`` (``trajectory_msgs/msg/
    JointTrajectory`` or ``nav_msgs/msg/Path``), as an MCAP ``ros2msg`` schema holds it."""
    name = datatype.replace("/msg/", "/")
    parts = [_FIELDS[name]]
    for used in _USES[name]:
        parts += [_SEPARATOR, f"MSG: {used}", _FIELDS[used]]
    return "\n".join(parts) + "\n"


def duration(seconds: float) -> dict[str, int]:
    """``builtin_interfaces/Duration`` (or ``Time``) of ``seconds`` >= 0, to the nanosecond."""
    whole = math.floor(seconds)
    nanos = round((seconds - whole) * 1e9)
    if nanos >= 1_000_000_000:  # rounding carried into the next second
        whole, nanos = whole + 1, nanos - 1_000_000_000
    return {"sec": int(whole), "nanosec": int(nanos)}


def _header(frame_id: str, stamp_s: float = 0.0) -> dict[str, Any]:
    return {"stamp": duration(stamp_s), "frame_id": frame_id}


def joint_trajectory_message(
    frame_id: str,
    joint_names: list[str],
    t: ArrayLike,
    positions: ArrayLike,
    velocities: ArrayLike | None = None,
) -> dict[str, Any]:
    """A ``trajectory_msgs/msg/JointTrajectory`` as a dict.

    Parameters
    ----------
    frame_id : str
        The header's frame (the arm's base link); the stamp is zero: start when received.
    joint_names : list of str
    t : array_like, shape (n,)
        ``time_from_start`` of each point (s).
    positions : array_like, shape (n, J)
    velocities : array_like, shape (n, J), optional
    """
    q = np.asarray(positions, dtype=np.float64)
    qd = None if velocities is None else np.asarray(velocities, dtype=np.float64)
    points = [
        {
            "positions": q[i].tolist(),
            "velocities": [] if qd is None else qd[i].tolist(),
            "accelerations": [],
            "effort": [],
            "time_from_start": duration(float(ti)),
        }
        for i, ti in enumerate(np.asarray(t, dtype=np.float64))
    ]
    return {"header": _header(frame_id), "joint_names": list(joint_names), "points": points}


def path_message(
    frame_id: str, t: ArrayLike, positions: ArrayLike, quaternions: ArrayLike
) -> dict[str, Any]:
    """A ``nav_msgs/msg/Path`` as a dict: one ``PoseStamped`` per waypoint, stamped with its time
    from the start.

    Parameters
    ----------
    frame_id : str
    t : array_like, shape (n,)
    positions : array_like, shape (n, 3)
        Metres, in ``frame_id``.
    quaternions : array_like, shape (n, 4)
        ``(x, y, z, w)``, in ``frame_id``.
    """
    xyz = np.asarray(positions, dtype=np.float64)
    quat = np.asarray(quaternions, dtype=np.float64)
    poses = [
        {
            "header": _header(frame_id, float(ti)),
            "pose": {
                "position": dict(zip("xyz", xyz[i].tolist())),
                "orientation": dict(zip("xyzw", quat[i].tolist())),
            },
        }
        for i, ti in enumerate(np.asarray(t, dtype=np.float64))
    ]
    return {"header": _header(frame_id), "poses": poses}
