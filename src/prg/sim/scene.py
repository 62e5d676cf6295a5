"""The PyBullet scene: a table, a sheet of paper, a 7-DOF arm and its pen; and its camera.

Every PyBullet call passes ``physicsClientId``; nothing uses PyBullet's default client, so
several scenes (and the IK's own kinematic copy of the arm, :class:`prg.sim.ik.IKSolver`) live
side by side.

The paper is a thin textured mesh (a quad with texture coordinates, written to a temporary OBJ
file) so that the ink can be shown on it: :meth:`Scene.show_ink` loads an image of the ink as the
paper's texture, and :meth:`Scene.render` takes a camera picture with the TinyRenderer (no
display needed). The pen is a visual-only cylinder that follows the flange
(:meth:`Scene.place_pen`); the inking is decided geometrically from the pen tip's height
(:func:`prg.sim.geometry.in_contact`), not by collision.
"""

from __future__ import annotations

import logging
import os
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prg.errors import PRGError, UsageError
from prg.sim.bullet import flange_pose, load_robot, pen_tip, pybullet, rotate
from prg.sim.robots import RobotSettings, pybullet_data_path
from prg.sim.settings import Camera, Paper  # Camera re-exported

log = logging.getLogger(__name__)

__all__ = ["TABLE_TOP_Z", "Camera", "Scene", "pybullet"]

TABLE_TOP_Z = 0.625  # pybullet_data/table/table.urdf: a 5 cm top centred at z = 0.6


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
            self.robot = load_robot(p, self.cid, robot)
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
        return flange_pose(self.p, self.cid, self.robot)

    def tip_pose(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Pen-tip position (m) and the pen's orientation (x, y, z, w) in the world."""
        tip, orn = pen_tip(self.p, self.cid, self.robot)
        return tip, np.asarray(orn)

    def place_pen(self) -> None:
        """Move the drawn pen to the flange (its tip at the pen offset)."""
        pos, orn = self.flange_pose()
        cfg = self.robot.config
        offset = np.asarray(cfg.pen_offset, dtype=np.float64)
        centre = offset - offset / np.linalg.norm(offset) * cfg.pen_length / 2
        self.p.resetBasePositionAndOrientation(
            self.pen, (pos + rotate(orn, centre)).tolist(), orn, physicsClientId=self.cid
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
