"""Inverse kinematics of the pen tip, held vertical and tip down, on a kinematic copy of the arm.

:class:`IKSolver` solves in its own DIRECT PyBullet client holding only the arm, so it can set
the solve's seed posture freely without disturbing a simulation. Each waypoint is solved with
PyBullet's null-space IK (rest pose, joint limits) and then refined by a plain solve seeded from
it (:class:`IKSettings`); :meth:`IKSolver.solve_path` seeds each waypoint with the previous
solution and raises :class:`UnreachableError`, naming the point, at the first one out of reach.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prg.errors import UsageError
from prg.sim.bullet import flange_pose, load_robot, pen_tip, pybullet, rotate
from prg.sim.robots import RobotSettings
from prg.sim.settings import IK_METHODS, IKSettings  # re-exported

__all__ = [
    "IK_METHODS",
    "PEN_DOWN",
    "IKSettings",
    "IKSolver",
    "UnreachableError",
    "pen_down",
]

PEN_DOWN = (1.0, 0.0, 0.0, 0.0)
"""Flange orientation (x, y, z, w) with its z axis pointing straight down: a rotation of pi about
x. The pen, along the flange's z axis, is then vertical, tip down."""


def pen_down(yaw: float) -> tuple[float, float, float, float]:
    """:data:`PEN_DOWN` turned by ``yaw`` (rad) about the vertical, (x, y, z, w)."""
    return (math.cos(yaw / 2), math.sin(yaw / 2), 0.0, 0.0)


class UnreachableError(UsageError):
    """An IK target the arm cannot reach with the pen vertical (names the point)."""


class IKSolver:
    """Inverse kinematics for the pen tip, on a kinematic copy of the arm in its own client.

    PyBullet's IK starts from the body's current joint state; a separate DIRECT client holding
    only the arm lets the solver set that seed freely without disturbing the simulation.

    Parameters
    ----------
    config : RobotSettings
    settings : IKSettings

    Attributes
    ----------
    orientation : tuple of float
        The flange orientation every solve asks for (x, y, z, w): the pen vertical, tip down,
        turned about the pen as in the rest pose.
    """

    def __init__(self, config: RobotSettings, settings: IKSettings | None = None) -> None:
        self.p = pybullet()
        self.settings = settings or IKSettings()
        self.cid = self.p.connect(self.p.DIRECT)
        try:
            self.robot = load_robot(self.p, self.cid, config)
        except BaseException:
            self.close()
            raise
        r = self.robot
        self._lower = r.lower.tolist()
        self._upper = r.upper.tolist()
        self._ranges = (r.upper - r.lower).tolist()
        self._rest = r.rest_movable.tolist()
        # hold the pen vertical with the flange turned about the pen as in the rest pose, so
        # the wrist does not spin to reach an arbitrary heading
        self.set_state(r.rest_movable)
        _, rest_orientation = flange_pose(self.p, self.cid, r)
        x_axis = rotate(rest_orientation, [1.0, 0.0, 0.0])
        self.orientation = pen_down(math.atan2(x_axis[1], x_axis[0]))
        self._flange_offset = rotate(self.orientation, config.pen_offset)

    def close(self) -> None:
        """Disconnect the solver's client (idempotent)."""
        if getattr(self, "cid", None) is not None:
            self.p.disconnect(physicsClientId=self.cid)
            self.cid = None

    def __enter__(self) -> IKSolver:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def set_state(self, q_movable: ArrayLike) -> None:
        """Put the kinematic copy in posture ``q_movable`` (one value per movable joint)."""
        self.p.resetJointStatesMultiDof(
            self.robot.body,
            list(self.robot.movable),
            [[float(q)] for q in q_movable],
            physicsClientId=self.cid,
        )

    def tip(self, q_movable: ArrayLike) -> NDArray[np.float64]:
        """Pen-tip position (world, m) in posture ``q_movable``."""
        self.set_state(q_movable)
        return self.current_tip()

    def current_tip(self) -> NDArray[np.float64]:
        """Pen-tip position (world, m) in the current posture of the kinematic copy."""
        return pen_tip(self.p, self.cid, self.robot)[0]

    def solve(
        self, tip: ArrayLike, seed: ArrayLike | None = None
    ) -> tuple[NDArray[np.float64], float]:
        """Joint positions putting the pen tip at ``tip`` (world, m), pen vertical, tip down.

        Parameters
        ----------
        tip : array_like, shape (3,)
        seed : array_like, shape (len(movable),), optional
            Start posture: the previous waypoint's solution. Without one the solve starts
            from the rest pose with ``cold_iterations``.

        Returns
        -------
        q : ndarray, shape (len(movable),)
            Held joints at their held values.
        error_m : float
            Distance of the reached tip from ``tip``; ``inf`` when the solution leaves the
            joint limits.
        """
        p, s, r = self.p, self.settings, self.robot
        target = np.asarray(tip, dtype=np.float64)
        flange = (target - self._flange_offset).tolist()
        self.set_state(self._rest if seed is None else seed)
        null_space = s.cold_iterations if seed is None else s.null_space_iterations
        refine = s.cold_iterations if seed is None else s.refine_iterations
        q = self._rest if seed is None else seed
        if s.method != "plain":
            q = p.calculateInverseKinematics(
                r.body,
                r.flange,
                flange,
                self.orientation,
                lowerLimits=self._lower,
                upperLimits=self._upper,
                jointRanges=self._ranges,
                restPoses=self._rest,
                maxNumIterations=null_space,
                residualThreshold=s.residual,
                physicsClientId=self.cid,
            )
        if s.method != "null_space":
            self.set_state(q)
            q = p.calculateInverseKinematics(
                r.body,
                r.flange,
                flange,
                self.orientation,
                maxNumIterations=refine,
                residualThreshold=s.residual,
                physicsClientId=self.cid,
            )
        q = np.asarray(q, dtype=np.float64)
        for j, value in r.held.items():
            q[r.movable.index(j)] = value
        self.set_state(q)
        error = float(np.linalg.norm(self.current_tip() - target))
        slack = 1e-6
        if np.any(q < r.lower - slack) or np.any(q > r.upper + slack):
            error = math.inf
        return q, error

    def solve_path(
        self,
        tips: ArrayLike,
        seed: ArrayLike | None = None,
        describe: Callable[[int], str] | None = None,
        progress: Callable[[int], object] | None = None,
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Solve a sequence of tip targets, each seeded with the previous solution.

        Parameters
        ----------
        tips : array_like, shape (n, 3)
            World positions (m).
        seed : array_like, optional
            Posture before the first target (default: a cold start from the rest pose).
        describe : callable, optional
            ``describe(i) -> str`` naming target ``i`` for the error message.
        progress : callable, optional
            Called with the number of targets solved since its last call (every 100).

        Returns
        -------
        q : ndarray, shape (n, len(movable))
        errors : ndarray, shape (n,)
            Tip errors (m).

        Raises
        ------
        UnreachableError
            At the first target whose error exceeds ``tolerance_mm`` (naming it).
        """
        targets = np.asarray(tips, dtype=np.float64)
        out = np.empty((len(targets), len(self.robot.movable)))
        errors = np.empty(len(targets))
        q = None if seed is None else np.asarray(seed, dtype=np.float64)
        for i, tip in enumerate(targets):
            q, err = self.solve(tip, q)
            if err * 1000.0 > self.settings.tolerance_mm:
                where = describe(i) if describe else f"({tip[0]:.4f}, {tip[1]:.4f}, {tip[2]:.4f}) m"
                what = "outside the joint limits" if math.isinf(err) else f"{err * 1000:.1f} mm off"
                raise UnreachableError(
                    f"robot {self.robot.config.name} cannot reach the pen-tip target {where} "
                    f"with the pen vertical (IK solution {what}): make the word smaller "
                    "(scale=...) or move it (paper.word_centre_cm=[x,y])"
                )
            out[i], errors[i] = q, err
            if progress is not None and ((i + 1) % 100 == 0 or i + 1 == len(targets)):
                progress((i % 100) + 1)
        return out, errors
