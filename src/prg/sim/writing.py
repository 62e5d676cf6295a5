"""The simulated robot writes a word: placement, workspace check, IK, position control, ink.

:func:`simulate_word` is the task's core, in steps that read top to bottom:

1. **place** the word: its DMP rollout (:func:`prg.pipeline.motion.word_samples`) scaled and
   moved to its place on the paper;
2. **plan and solve**: refuse a word that does not fit the arm's reachable workspace there (one
   line giving the size that would fit, :func:`prg.sim.workspace.check_workspace`), plan the
   pen's motion (:mod:`prg.sim.plan`) and solve the inverse kinematics of every waypoint
   (:class:`prg.sim.ik.IKSolver`: null-space IK for posture, refined by a plain solve seeded
   from it) — nothing has moved yet;
3. **write**: run the physics with position control towards the interpolated joint targets,
   recording joint positions, the pen tip and the ink (tip samples within the contact band of
   the paper), and take a picture of the page.

It returns a :class:`SimResult` with the tracking error between commanded and inked path.
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from prg.files import staged_outputs, write_json
from prg.pipeline.motion import word_samples  # re-exported
from prg.pipeline.word import WordTrajectory
from prg.sim.geometry import (
    bounding_box,
    in_contact,
    max_ink_gap,
    place_points,
    runs,
    tracking_error,
)
from prg.sim.ik import IKSolver
from prg.sim.plan import PHASES, MotionPlan, plan_motion
from prg.sim.robots import RobotSettings
from prg.sim.scene import Scene
from prg.sim.settings import ControlSettings, SimSettings
from prg.sim.workspace import ReachMap, check_workspace

log = logging.getLogger(__name__)

__all__ = ["SimResult", "simulate_word", "word_samples"]


# ----------------------------------------------------------------------------- result


@dataclass
class SimResult:
    """What the simulated robot did.

    Attributes
    ----------
    text : str
    robot : RobotSettings
    settings : SimSettings
    plan : MotionPlan
        The commanded pen-tip waypoints (paper frame, cm).
    q_plan : ndarray, shape (n_waypoints, n_movable)
        IK solution of each waypoint.
    ik_error_m : ndarray, shape (n_waypoints,)
        Pen-tip error of each IK solution.
    t : ndarray, shape (n_steps,)
        Simulated time of each physics step (s), after the step.
    q : ndarray, shape (n_steps, n_arm)
        Measured arm joint positions (rad).
    q_target : ndarray, shape (n_steps, n_arm)
        Commanded arm joint positions.
    tip_world : ndarray, shape (n_steps, 3)
        Pen tip (m, world).
    tip_quaternion : ndarray, shape (n_steps, 4)
        Pen (flange) orientation (x, y, z, w).
    tip_paper : ndarray, shape (n_steps, 3)
        Pen tip in the paper frame (cm): ``x, y, height``.
    commanded : ndarray, shape (n_steps, 3)
        The plan interpolated at ``t`` (paper frame, cm).
    contact : ndarray of bool, shape (n_steps,)
        Tip within the contact band: ink.
    step_stroke : ndarray of int, shape (n_steps,)
        The commanded stroke each step belongs to (``-1``: none).
    placement : dict
        ``anchor_cm``, ``centre_cm``, ``scale``, word size.
    wall_s : float
        Wall-clock seconds of the physics loop.
    ik_wall_s : float
        Wall-clock seconds of the inverse kinematics.
    page : ndarray, shape (H, W, 3) or None
        TinyRenderer picture of the page after writing.
    arm_joint_names : list of str
    """

    text: str
    robot: RobotSettings
    settings: SimSettings
    plan: MotionPlan
    q_plan: NDArray[np.float64]
    ik_error_m: NDArray[np.float64]
    t: NDArray[np.float64]
    q: NDArray[np.float64]
    q_target: NDArray[np.float64]
    tip_world: NDArray[np.float64]
    tip_quaternion: NDArray[np.float64]
    tip_paper: NDArray[np.float64]
    commanded: NDArray[np.float64]
    contact: NDArray[np.bool_]
    step_stroke: NDArray[np.int64]
    placement: dict
    wall_s: float
    ik_wall_s: float
    page: NDArray[np.uint8] | None = None

    @property
    def arm_joint_names(self) -> list[str]:
        return list(self.robot.arm_joints)

    @property
    def sim_s(self) -> float:
        """Simulated seconds."""
        return float(self.t[-1]) if len(self.t) else 0.0

    def ink_strokes(self) -> list[NDArray[np.float64]]:
        """The ink: consecutive in-contact tip samples, each ``(m, 2)`` in cm (paper frame)."""
        return [self.tip_paper[a:b, :2] for a, b in runs(self.contact)]

    def save(self, folder: str | os.PathLike) -> Path:
        """``ink.png``, ``ink.svg``, ``page.png``, ``joints.csv``, ``joints.npz``, ``metrics.json``
        into ``folder``, all or nothing (through a staging folder; files already in ``folder``
        under other names are kept), as ``prg-simulate`` writes them."""
        from PIL import Image

        from prg.sim.ink import ink_png, ink_svg

        folder = Path(folder)
        with staged_outputs(folder) as staging:
            strokes = self.ink_strokes()
            ink_png(strokes, staging / "ink.png")
            ink_svg(strokes, staging / "ink.svg", title=f"{self.text} ({self.robot.name})")
            if self.page is not None:
                Image.fromarray(self.page).save(staging / "page.png")
            names = self.arm_joint_names
            columns = np.column_stack(
                [self.t, self.q, self.tip_paper, self.contact.astype(np.float64)]
            )
            header = ",".join(["t_s", *names, "tip_x_cm", "tip_y_cm", "tip_height_cm", "ink"])
            fmt = ["%.6f"] + ["%.8f"] * len(names) + ["%.6f"] * 3 + ["%d"]
            np.savetxt(
                staging / "joints.csv", columns, delimiter=",", header=header, comments="", fmt=fmt
            )
            np.savez_compressed(
                staging / "joints.npz",
                t=self.t,
                joint_names=np.array(names),
                q=self.q,
                q_target=self.q_target,
                tip_world=self.tip_world,
                tip_quaternion=self.tip_quaternion,
                tip_paper=self.tip_paper,
                commanded=self.commanded,
                contact=self.contact,
                plan_t=self.plan.t,
                plan_tip=self.plan.tip,
                plan_pen_down=self.plan.pen_down,
                plan_stroke=self.plan.stroke,
                plan_phase=self.plan.phase,
                q_plan=self.q_plan,
            )
            write_json(staging / "metrics.json", self.metrics)
        return folder

    @cached_property
    def metrics(self) -> dict:
        """Tracking error, ink gaps, timing and size (the ``metrics.json`` of a run)."""
        commanded = self.plan.strokes()
        ink = self.ink_strokes()
        errors = tracking_error(commanded, ink)
        gap = max_ink_gap(
            commanded, self.tip_paper[self.contact, :2], self.step_stroke[self.contact]
        )
        writing = np.isin(self.plan.phase, [PHASES.index("write")])
        return {
            "text": self.text,
            "robot": self.robot.name,
            "tracking_error_mean_mm": errors["mean_mm"],
            "tracking_error_max_mm": errors["max_mm"],
            "command_to_ink_max_mm": errors["command_to_ink_max_mm"],
            "ink_to_command_max_mm": errors["ink_to_command_max_mm"],
            "max_ink_gap_mm": gap * 10.0,
            "pen_step_mm": self.plan.pen_step_cm() * 10.0,
            "ink_strokes": len(ink),
            "commanded_strokes": len(commanded),
            "ink_points": int(self.contact.sum()),
            "ik_error_mean_mm": float(self.ik_error_m.mean() * 1000.0),
            "ik_error_max_mm": float(self.ik_error_m.max() * 1000.0),
            "rest_distance_max_rad": float(
                np.abs(self.q - np.asarray(self.robot.rest_pose)).max(axis=1).max()
            ),
            "writing_s": float(np.ptp(self.plan.t[writing])) if writing.any() else 0.0,
            "sim_s": self.sim_s,
            "wall_s": self.wall_s,
            "ik_wall_s": self.ik_wall_s,
            "realtime_factor": self.sim_s / max(self.wall_s + self.ik_wall_s, 1e-9),
            "physics_steps": len(self.t),
            "waypoints": len(self.plan.t),
            "scale": self.placement["scale"],
            "word_width_cm": self.placement["width_cm"],
            "word_height_cm": self.placement["height_cm"],
        }


# ----------------------------------------------------------------------------- the run


def simulate_word(
    word: WordTrajectory,
    robot: RobotSettings | str,
    settings: SimSettings | None = None,
    *,
    gui: bool = False,
    progress: bool = False,
    render: bool = True,
) -> SimResult:
    """Write ``word`` on the paper with the simulated arm.

    Parameters
    ----------
    word : WordTrajectory
        From ``prg-write`` (``word.json``); its DMP gives the pen-down motion and its timing.
    robot : RobotSettings or str
        The arm, or the name of one described in ``conf/robot/`` (``"panda"``, ``"iiwa"``:
        :meth:`RobotSettings.named`).
    settings : SimSettings, optional
        Default ``SimSettings()``: ``conf/simulate.yaml``'s values.
    gui : bool
        PyBullet GUI instead of DIRECT (needs a display).
    progress : bool
        Show progress bars over the IK waypoints and the physics steps.
    render : bool
        Take the TinyRenderer picture of the page at the end.

    Returns
    -------
    SimResult

    Raises
    ------
    UsageError
        If the word does not fit the workspace (the size that fits is given) or an IK target is
        unreachable (the point is named); nothing has been simulated then.
    """
    Scene.check_gui(gui)
    robot = RobotSettings.named(robot) if isinstance(robot, str) else robot
    s = settings or SimSettings()
    placed = _place(word, s)
    solved = _plan_and_solve(placed, word.text, robot, s, progress)
    result = _write(placed, solved, word.text, robot, s, gui=gui, progress=progress, render=render)
    _log_result(result)
    return result


@dataclass(frozen=True)
class _Placed:
    """The word's motion and where it goes on the paper."""

    samples: NDArray[np.float64]  # (n, 2): the word's own frame (cm), unscaled
    t: NDArray[np.float64]  # (n,) s
    pen_down: NDArray[np.bool_]  # (n,)
    low: NDArray[np.float64]  # bounding box of samples
    high: NDArray[np.float64]
    centre: NDArray[np.float64]  # where the box's centre goes (paper frame, cm)
    scale: float

    @property
    def anchor(self) -> NDArray[np.float64]:
        return (self.low + self.high) / 2

    @property
    def size_cm(self) -> NDArray[np.float64]:
        """Width and height on the paper."""
        return (self.high - self.low) * self.scale

    def on_paper(self) -> NDArray[np.float64]:
        """The samples placed on the paper (paper frame, cm)."""
        return place_points(self.samples, self.anchor, self.scale, self.centre)

    def as_dict(self) -> dict[str, Any]:
        """:attr:`SimResult.placement`."""
        width, height = self.size_cm
        return {
            "anchor_cm": self.anchor.tolist(),
            "centre_cm": self.centre.tolist(),
            "scale": self.scale,
            "width_cm": float(width),
            "height_cm": float(height),
        }


def _place(word: WordTrajectory, s: SimSettings) -> _Placed:
    """Step 1: the word's motion at the waypoint spacing and tempo, and its place on the paper."""
    samples, t, down = word_samples(word, s.control.waypoint_dt, s.tempo)
    low, high = bounding_box(samples)
    centre = np.asarray(s.word_centre_cm, dtype=np.float64)
    return _Placed(samples, t, down, low, high, centre, s.scale)


@dataclass(frozen=True)
class _Solved:
    """The pen's waypoints and the joint positions reaching them."""

    plan: MotionPlan
    q: NDArray[np.float64]  # (n_waypoints, n_movable)
    error_m: NDArray[np.float64]  # (n_waypoints,) pen-tip error of each solution
    wall_s: float  # wall-clock seconds of the workspace check and the IK


def _plan_and_solve(
    placed: _Placed, text: str, robot: RobotSettings, s: SimSettings, progress: bool
) -> _Solved:
    """Step 2: refuse a word that does not fit the workspace, plan the pen's motion from the
    rest posture and back, and solve the IK of every waypoint."""
    start = time.perf_counter()
    with IKSolver(robot, s.ik) as ik:
        reach = ReachMap(ik, s.paper, (0.0, s.motion.lift_cm), s.workspace_step_cm)
        check_workspace(
            placed.samples, placed.anchor, placed.centre, s.scale, reach, robot.name, text
        )
        home = s.paper.to_paper(ik.tip(ik.robot.rest_movable))[0]
        plan = plan_motion(
            placed.on_paper(), placed.t, placed.pen_down, home, s.motion, s.control.waypoint_dt
        )
        with _progress(
            len(plan.t), f"{robot.name}: inverse kinematics", progress, "waypoint"
        ) as bar:
            q, error = ik.solve_path(
                s.paper.to_world(plan.tip),
                describe=_describe(plan),
                progress=None if bar is None else bar.update,
            )
        log.info(
            "IK: %d waypoints (%d workspace nodes) in %.2f s, tip error mean %.4f max %.4f mm",
            len(plan.t),
            reach.solved,
            time.perf_counter() - start,
            error.mean() * 1000,
            error.max() * 1000,
        )
    return _Solved(plan, q, error, time.perf_counter() - start)


def _describe(plan: MotionPlan) -> Callable[[int], str]:
    """Names waypoint ``i`` for an unreachable-target message."""

    def describe(i: int) -> str:
        x, y, h = plan.tip[i]
        return (
            f"({x:.1f}, {y:.1f}) cm on the paper, {h:.1f} cm above it "
            f"({PHASES[plan.phase[i]]} at t = {plan.t[i]:.2f} s)"
        )

    return describe


@dataclass(frozen=True)
class _Commands:
    """What the position control is told at each physics step."""

    t: NDArray[np.float64]  # (n_steps,) simulated time after each step
    q: NDArray[np.float64]  # (n_steps, n_movable) joint targets, the waypoints interpolated
    qd: NDArray[np.float64]  # (n_steps, n_movable) their velocity (feed-forward)
    tip: NDArray[np.float64]  # (n_steps, 3) the plan at t (paper frame, cm)
    stroke: NDArray[np.int64]  # (n_steps,) the commanded stroke of each step (-1: none)


def _commands(solved: _Solved, ctl: ControlSettings) -> _Commands:
    """Joint targets every physics step: the waypoints' solutions interpolated linearly, with
    the velocity of the interval each step falls in; held at the end for ``settle_s``."""
    plan, q_plan = solved.plan, solved.q
    n_steps = math.ceil((plan.duration_s + ctl.settle_s) / ctl.time_step)
    t = (np.arange(n_steps) + 1) * ctl.time_step
    targets = np.column_stack([np.interp(t, plan.t, q_plan[:, j]) for j in range(q_plan.shape[1])])
    interval = np.clip(np.searchsorted(plan.t, t, side="right") - 1, 0, len(plan.t) - 2)
    velocities = (q_plan[interval + 1] - q_plan[interval]) / np.diff(plan.t)[interval][:, None]
    velocities[t >= plan.t[-1]] = 0.0
    commanded = np.column_stack([np.interp(t, plan.t, plan.tip[:, d]) for d in range(3)])
    step_stroke = plan.stroke[np.clip(np.searchsorted(plan.t, t, side="left"), 0, len(plan.t) - 1)]
    return _Commands(t, targets, velocities, commanded, step_stroke)


def _write(
    placed: _Placed,
    solved: _Solved,
    text: str,
    robot: RobotSettings,
    s: SimSettings,
    *,
    gui: bool,
    progress: bool,
    render: bool,
) -> SimResult:
    """Step 3: the physics, from the first waypoint's posture, and the picture of the page."""
    ctl = s.control
    cmd = _commands(solved, ctl)
    with Scene(robot, s.paper, gui=gui, time_step=ctl.time_step) as scene:
        scene.reset(solved.q[0])
        arm = list(scene.robot.arm_in_movable)
        with _progress(len(cmd.t), f"{robot.name} writes {text!r}", progress, "step") as bar:
            q, tip, orn, wall = _run(scene, cmd, arm, ctl, gui, bar)
        tip_paper = s.paper.to_paper(tip)
        result = SimResult(
            text=text,
            robot=robot,
            settings=s,
            plan=solved.plan,
            q_plan=solved.q,
            ik_error_m=solved.error_m,
            t=cmd.t,
            q=q,
            q_target=cmd.q[:, arm],
            tip_world=tip,
            tip_quaternion=orn,
            tip_paper=tip_paper,
            commanded=cmd.tip,
            contact=in_contact(tip_paper[:, 2], ctl.contact_band_mm),
            step_stroke=cmd.stroke,
            placement=placed.as_dict(),
            wall_s=wall,
            ik_wall_s=solved.wall_s,
        )
        if render:
            result.page = _page(scene, result, placed)
    return result


def _run(
    scene: Scene,
    cmd: _Commands,
    arm: list[int],
    ctl: ControlSettings,
    gui: bool,
    bar: Any,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], float]:
    """Step the physics under position control; the arm joints, pen tip and pen orientation
    after every step, and the wall-clock seconds it took."""
    n_steps = len(cmd.t)
    q = np.empty((n_steps, len(arm)))
    tip = np.empty((n_steps, 3))
    orn = np.empty((n_steps, 4))
    start = time.perf_counter()
    for i in range(n_steps):
        scene.command(cmd.q[i], cmd.qd[i], ctl.position_gain, ctl.velocity_gain)
        scene.step()
        q[i] = scene.joint_positions()[arm]
        tip[i], orn[i] = scene.tip_pose()
        if gui:
            scene.place_pen()
        if bar is not None and (i + 1) % 240 == 0:
            bar.update(240)
    wall = time.perf_counter() - start
    if bar is not None:
        bar.update(n_steps - bar.n)
    return q, tip, orn, wall


def _page(scene: Scene, result: SimResult, placed: _Placed) -> NDArray[np.uint8]:
    """The ink on the paper's texture, and a TinyRenderer picture framing the word."""
    from prg.sim.ink import page_texture

    paper = result.settings.paper
    scene.show_ink(page_texture(result.ink_strokes(), paper))
    return scene.render(
        result.settings.camera,
        target=paper.to_world(placed.centre[None])[0],
        extent_m=placed.size_cm / 100.0,
    )


def _log_result(result: SimResult) -> None:
    m = result.metrics
    log.info(
        "%s wrote %r: tracking error mean %.3f mm, max %.3f mm; longest ink gap %.3f mm "
        "(pen step %.3f mm); %.1f s simulated in %.1f s",
        result.robot.name,
        result.text,
        m["tracking_error_mean_mm"],
        m["tracking_error_max_mm"],
        m["max_ink_gap_mm"],
        m["pen_step_mm"],
        m["sim_s"],
        m["wall_s"] + m["ik_wall_s"],
    )


@contextmanager
def _progress(total: int, description: str, enabled: bool, unit: str) -> Iterator[Any]:
    """A tqdm bar over ``total`` units (None when not ``enabled``), closed at the end."""
    if not enabled:
        yield None
        return
    from tqdm.auto import tqdm

    bar = tqdm(total=total, desc=description, unit=unit, leave=False)
    try:
        yield bar
    finally:
        bar.close()
