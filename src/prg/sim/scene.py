"""The PyBullet scene: a table, a sheet of paper, a 7-DOF arm and its pen; and the arm's IK.

Every PyBullet call passes ``physicsClientId``; nothing uses PyBullet's default client, so
several scenes (and the IK's own kinematic copy of the arm, :class:`IKSolver`) live side by side.

The paper is a thin textured mesh (a quad with texture coordinates, written to a temporary OBJ
file) so that the ink can be shown on it: :meth:`Scene.show_ink` loads an image of the ink as the
paper's texture, and :meth:`Scene.render` takes a camera picture with the TinyRenderer (no
display needed). The pen is a visual-only cylinder that follows the flange
(:meth:`Scene.place_pen`); the inking is decided geometrically from the pen tip's height
(:func:`prg.sim.geometry.in_contact`), not by collision.
"""

from __future__ import annotations

import logging
import math
import os
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prg.errors import PRGError, UsageError
from prg.sim.geometry import Paper
from prg.sim.robots import LoadedRobot, RobotSettings, pybullet_data_path

log = logging.getLogger(__name__)

__all__ = [
    "IK_METHODS",
    "PEN_DOWN",
    "Camera",
    "IKSettings",
    "IKSolver",
    "Scene",
    "UnreachableError",
    "pen_down",
    "pybullet",
]

PEN_DOWN = (1.0, 0.0, 0.0, 0.0)
"""Flange orientation (x, y, z, w) with its z axis pointing straight down: a rotation of pi about
x. The pen, along the flange's z axis, is then vertical, tip down."""


def pen_down(yaw: float) -> tuple[float, float, float, float]:
    """:data:`PEN_DOWN` turned by ``yaw`` (rad) about the vertical, (x, y, z, w)."""
    return (math.cos(yaw / 2), math.sin(yaw / 2), 0.0, 0.0)


IK_METHODS = ("refined", "null_space", "plain")
TABLE_TOP_Z = 0.625  # pybullet_data/table/table.urdf: a 5 cm top centred at z = 0.6


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


class UnreachableError(UsageError):
    """An IK target the arm cannot reach with the pen vertical (names the point)."""


@dataclass(frozen=True)
class IKSettings:
    """Inverse kinematics: null-space IK for posture, refined by a plain IK solve seeded from it.

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

    null_space_iterations: int = 20
    refine_iterations: int = 100
    cold_iterations: int = 100
    residual: float = 1e-7
    tolerance_mm: float = 0.5
    method: str = "refined"

    def __post_init__(self) -> None:
        if self.method not in IK_METHODS:
            raise UsageError(f"ik.method {self.method!r}: choose {', '.join(IK_METHODS)}")
        for name in ("null_space_iterations", "refine_iterations", "cold_iterations"):
            value = getattr(self, name)
            if isinstance(value, bool) or int(value) != value or value < 1:
                raise UsageError(f"ik.{name} must be a positive integer, got {value!r}")
        for name in ("residual", "tolerance_mm"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise UsageError(f"ik.{name} must be positive, got {getattr(self, name)!r}")


def _rotate(quaternion: ArrayLike, vector: ArrayLike) -> NDArray[np.float64]:
    """Rotate ``vector`` (3,) by a unit quaternion (x, y, z, w)."""
    x, y, z, w = quaternion
    v = np.asarray(vector, dtype=np.float64)
    u = np.array([x, y, z])
    return v + 2.0 * np.cross(u, np.cross(u, v) + w * v)


def _load_robot(p: ModuleType, cid: int, config: RobotSettings) -> LoadedRobot:
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
            self.robot = _load_robot(self.p, self.cid, config)
        except BaseException:
            self.close()
            raise
        r = self.robot
        self._lower = r.lower.tolist()
        self._upper = r.upper.tolist()
        self._ranges = (r.upper - r.lower).tolist()
        self._rest = r.rest_movable.tolist()
        self._offset = np.asarray(config.pen_offset, dtype=np.float64)
        # hold the pen vertical with the flange turned about the pen as in the rest pose, so
        # the wrist does not spin to reach an arbitrary heading
        self.set_state(r.rest_movable)
        _, rest_orientation = self._flange()
        x_axis = _rotate(rest_orientation, [1.0, 0.0, 0.0])
        self.orientation = pen_down(math.atan2(x_axis[1], x_axis[0]))
        self._flange_offset = _rotate(self.orientation, self._offset)

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

    def _flange(self) -> tuple[NDArray[np.float64], tuple[float, float, float, float]]:
        state = self.p.getLinkState(
            self.robot.body,
            self.robot.flange,
            computeForwardKinematics=True,
            physicsClientId=self.cid,
        )
        return np.asarray(state[4]), state[5]

    def current_tip(self) -> NDArray[np.float64]:
        """Pen-tip position (world, m) in the current posture of the kinematic copy."""
        position, orientation = self._flange()
        return position + _rotate(orientation, self._offset)

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


@dataclass(frozen=True)
class Camera:
    """A TinyRenderer camera looking down at the paper.

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

    width: int = 1024
    height: int = 768
    distance: float | None = None
    yaw: float = -90.0
    pitch: float = -89.0
    fov: float = 45.0

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            value = getattr(self, name)
            if isinstance(value, bool) or int(value) != value or not 16 <= value <= 8192:
                raise UsageError(f"camera.{name} must be a whole number of pixels in [16, 8192]")
        if self.distance is not None and not (math.isfinite(self.distance) and self.distance > 0):
            raise UsageError(f"camera.distance must be positive (m) or null, got {self.distance!r}")
        if not 1.0 <= self.fov <= 170.0:
            raise UsageError(f"camera.fov must be in [1, 170] degrees, got {self.fov!r}")

    def framing_distance(
        self, extent_m: ArrayLike, margin: float = 1.4, least: float = 0.08
    ) -> float:
        """Distance at which a region ``extent_m`` = (width, height) fills the picture, times
        ``margin``, and at least ``least`` m wide."""
        half_v = math.radians(self.fov) / 2
        half_h = math.atan(math.tan(half_v) * self.width / self.height)
        w, h = np.maximum(np.asarray(extent_m, dtype=np.float64) * margin, least) / 2
        return float(max(w / math.tan(half_h), h / math.tan(half_v)))


class Scene:
    """A PyBullet world: table, paper, arm and pen; one client id, held here.

    Parameters
    ----------
    robot : RobotSettings
    paper : Paper
    gui : bool
        Connect with the GUI (needs a display) instead of DIRECT.
    time_step : float
        Physics step (s).

    Attributes
    ----------
    cid : int
        The PyBullet client id every call passes.
    robot : LoadedRobot
    """

    def __init__(
        self, robot: RobotSettings, paper: Paper, gui: bool = False, time_step: float = 1 / 240
    ) -> None:
        self.check_gui(gui)
        self.p = p = pybullet()
        self.paper = paper
        self.time_step = float(time_step)
        self._tmp = tempfile.TemporaryDirectory(prefix="prg-sim-")
        self._textures = 0
        self.cid = p.connect(p.GUI if gui else p.DIRECT)
        if self.cid < 0:
            self._tmp.cleanup()
            raise PRGError("PyBullet could not connect (GUI needs a display; use gui=false)")
        try:
            p.setGravity(0, 0, -9.81, physicsClientId=self.cid)
            p.setTimeStep(self.time_step, physicsClientId=self.cid)
            data = pybullet_data_path()
            self.plane = p.loadURDF(str(data / "plane.urdf"), physicsClientId=self.cid)
            self.table = p.loadURDF(
                str(data / "table" / "table.urdf"),
                basePosition=[paper.centre[0], 0.0, 0.0],
                useFixedBase=True,
                physicsClientId=self.cid,
            )
            self.paper_body = self._add_paper()
            self.robot = _load_robot(p, self.cid, robot)
            self.pen = self._add_pen()
            self.reset(self.robot.rest_movable)
        except BaseException:
            self.close()
            raise

    @staticmethod
    def check_gui(gui: bool) -> None:
        """Refuse ``gui=True`` without a display: PyBullet's GUI would end the whole process
        ("cannot connect to X server") instead of raising."""
        if gui and sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
            raise UsageError("gui=true needs a display (DISPLAY is not set): use gui=false")

    # ------------------------------------------------------------------ building
    def _add_paper(self) -> int:
        p, paper = self.p, self.paper
        w, h = (np.asarray(paper.size_cm) / 100.0).tolist()
        mesh = Path(self._tmp.name) / "paper.obj"
        # a quad in the paper frame, texture u along x, v along y (v = 1 at the top edge)
        mesh.write_text(
            "o paper\n"
            f"v {-w / 2} {-h / 2} 0\nv {w / 2} {-h / 2} 0\nv {w / 2} {h / 2} 0\nv {-w / 2} {h / 2} 0\n"
            "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n"
            "f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n"
        )
        visual = p.createVisualShape(
            p.GEOM_MESH,
            fileName=str(mesh),
            rgbaColor=[1, 1, 1, 1],
            physicsClientId=self.cid,
        )
        collision = p.createCollisionShape(
            p.GEOM_BOX,
            halfExtents=[w / 2, h / 2, paper.thickness_m / 2],
            collisionFramePosition=[0, 0, -paper.thickness_m / 2],
            physicsClientId=self.cid,
        )
        return p.createMultiBody(
            baseMass=0,
            baseCollisionShapeIndex=collision,
            baseVisualShapeIndex=visual,
            basePosition=list(paper.centre),
            baseOrientation=list(paper.quaternion),
            physicsClientId=self.cid,
        )

    def _add_pen(self) -> int:
        p, cfg = self.p, self.robot.config
        visual = p.createVisualShape(
            p.GEOM_CYLINDER,
            radius=cfg.pen_radius,
            length=cfg.pen_length,
            rgbaColor=[0.1, 0.2, 0.7, 1.0],
            physicsClientId=self.cid,
        )
        return p.createMultiBody(
            baseMass=0,
            baseVisualShapeIndex=visual,
            basePosition=[0, 0, 0],
            physicsClientId=self.cid,
        )

    # ------------------------------------------------------------------ state
    def reset(self, q_movable: ArrayLike) -> None:
        """Teleport the arm to ``q_movable`` at rest and hold it there."""
        r = self.robot
        for j, q in zip(r.movable, q_movable):
            self.p.resetJointState(r.body, j, float(q), 0.0, physicsClientId=self.cid)
        self.place_pen()

    def joint_positions(self) -> NDArray[np.float64]:
        """Current positions of the movable joints, shape (len(movable),)."""
        states = self.p.getJointStates(
            self.robot.body, self.robot.movable, physicsClientId=self.cid
        )
        return np.array([s[0] for s in states])

    def flange_pose(self) -> tuple[NDArray[np.float64], tuple[float, float, float, float]]:
        """Flange position (m) and orientation (x, y, z, w) in the world."""
        state = self.p.getLinkState(
            self.robot.body,
            self.robot.flange,
            computeForwardKinematics=True,
            physicsClientId=self.cid,
        )
        return np.asarray(state[4]), state[5]

    def tip_pose(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Pen-tip position (m) and the pen's orientation (x, y, z, w) in the world."""
        pos, orn = self.flange_pose()
        return pos + _rotate(orn, self.robot.config.pen_offset), np.asarray(orn)

    def place_pen(self) -> None:
        """Move the drawn pen to the flange (its tip at the pen offset)."""
        pos, orn = self.flange_pose()
        cfg = self.robot.config
        offset = np.asarray(cfg.pen_offset, dtype=np.float64)
        centre = offset - offset / np.linalg.norm(offset) * cfg.pen_length / 2
        self.p.resetBasePositionAndOrientation(
            self.pen, (pos + _rotate(orn, centre)).tolist(), orn, physicsClientId=self.cid
        )

    def command(
        self,
        q_target: ArrayLike,
        qd_target: ArrayLike,
        position_gain: float,
        velocity_gain: float,
    ) -> None:
        """Position control of every movable joint towards ``q_target`` (with velocity
        feed-forward ``qd_target``), at the URDF's force limits."""
        r = self.robot
        n = len(r.movable)
        self.p.setJointMotorControlArray(
            r.body,
            r.movable,
            self.p.POSITION_CONTROL,
            targetPositions=np.asarray(q_target, dtype=float).tolist(),
            targetVelocities=np.asarray(qd_target, dtype=float).tolist(),
            forces=r.max_force.tolist(),
            positionGains=[position_gain] * n,
            velocityGains=[velocity_gain] * n,
            physicsClientId=self.cid,
        )

    def step(self) -> None:
        """One physics step of ``time_step`` seconds."""
        self.p.stepSimulation(physicsClientId=self.cid)

    # ------------------------------------------------------------------ ink and camera
    def show_ink(self, image: NDArray[np.uint8]) -> None:
        """Use ``image`` (H, W, 3 uint8; row 0 = the top edge of the page) as the paper's
        texture."""
        from PIL import Image

        path = Path(self._tmp.name) / f"ink-{self._textures}.png"
        self._textures += 1
        # PyBullet flips textures on loading: the image's first row lands at v = 1, the top edge
        # of the paper quad (see _add_paper), so the page is stored as it is seen
        Image.fromarray(np.ascontiguousarray(image)).save(path)
        texture = self.p.loadTexture(str(path), physicsClientId=self.cid)
        self.p.changeVisualShape(
            self.paper_body, -1, textureUniqueId=texture, physicsClientId=self.cid
        )

    def render(
        self,
        camera: Camera | None = None,
        target: ArrayLike | None = None,
        extent_m: ArrayLike = (0.1, 0.1),
    ) -> NDArray[np.uint8]:
        """A TinyRenderer picture of the paper (and whatever is above it), shape (H, W, 3).

        Parameters
        ----------
        camera : Camera, optional
        target : array_like, shape (3,), optional
            World point the camera looks at (default: the paper's centre).
        extent_m : array_like, shape (2,)
            Size of the region to frame when ``camera.distance`` is None.
        """
        cam = camera or Camera()
        p = self.p
        self.place_pen()
        distance = cam.distance if cam.distance is not None else cam.framing_distance(extent_m)
        view = p.computeViewMatrixFromYawPitchRoll(
            cameraTargetPosition=list(self.paper.centre if target is None else target),
            distance=distance,
            yaw=cam.yaw,
            pitch=cam.pitch,
            roll=0.0,
            upAxisIndex=2,
            physicsClientId=self.cid,
        )
        return self._capture(view, (cam.width, cam.height), cam.fov, (0.3, -0.2, 1.0), False)

    def render_view(
        self,
        eye: ArrayLike,
        target: ArrayLike,
        size: tuple[int, int] = (900, 600),
        fov: float = 40.0,
        up: ArrayLike = (0.0, 0.0, 1.0),
        light_direction: ArrayLike = (0.4, -0.6, 1.0),
        shadow: bool = True,
    ) -> NDArray[np.uint8]:
        """A TinyRenderer picture from any viewpoint (e.g. a 3/4 view of the arm for figures).

        Parameters
        ----------
        eye, target : array_like, shape (3,)
            Camera position and the point it looks at (world, m).
        size : (width, height)
            Pixels.
        fov : float
            Vertical field of view (degrees).
        up : array_like, shape (3,)
            The world direction shown upwards.
        light_direction, shadow
            The TinyRenderer's directional light (towards the light) and its shadows.

        Returns
        -------
        ndarray of uint8, shape (height, width, 3)
        """
        self.place_pen()
        view = self.p.computeViewMatrix(
            cameraEyePosition=[float(v) for v in eye],
            cameraTargetPosition=[float(v) for v in target],
            cameraUpVector=[float(v) for v in up],
            physicsClientId=self.cid,
        )
        return self._capture(view, size, fov, light_direction, shadow)

    def _capture(
        self,
        view: Any,
        size: tuple[int, int],
        fov: float,
        light_direction: ArrayLike,
        shadow: bool,
    ) -> NDArray[np.uint8]:
        p = self.p
        width, height = (int(v) for v in size)
        proj = p.computeProjectionMatrixFOV(
            fov=fov, aspect=width / height, nearVal=0.01, farVal=5.0, physicsClientId=self.cid
        )
        _, _, rgba, _, _ = p.getCameraImage(
            width,
            height,
            viewMatrix=view,
            projectionMatrix=proj,
            renderer=p.ER_TINY_RENDERER,
            lightDirection=[float(v) for v in light_direction],
            shadow=int(shadow),
            physicsClientId=self.cid,
        )
        return np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)[..., :3]

    # ------------------------------------------------------------------ lifetime
    def close(self) -> None:
        """Disconnect and remove the temporary files (idempotent)."""
        if getattr(self, "cid", None) is not None and self.cid >= 0:
            self.p.disconnect(physicsClientId=self.cid)
        self.cid = None
        self._tmp.cleanup()

    def __enter__(self) -> Scene:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
