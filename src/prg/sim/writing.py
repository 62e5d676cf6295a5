"""The simulated robot writes a word: placement, workspace check, IK, position control, ink.

:func:`simulate_word` is the task's core: it maps the word's DMP rollout onto the paper,
refuses a word that does not fit the arm's reachable workspace there (one line giving the size
that would fit, :func:`check_workspace`), plans the pen's motion (:mod:`prg.sim.plan`), solves the
inverse kinematics of every waypoint (:class:`prg.sim.scene.IKSolver`: null-space IK for
posture, refined by a plain solve seeded from it), and runs the physics with position control,
recording joint positions, the pen tip and the ink (tip samples within the contact band of the
paper). It returns a :class:`SimResult` with the tracking error between commanded and inked path.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from prg.errors import UsageError
from prg.pipeline.word import WordTrajectory
from prg.sim.geometry import (
    Paper,
    bounding_box,
    in_contact,
    max_ink_gap,
    pen_down_samples,
    place_points,
    runs,
    tracking_error,
)
from prg.sim.plan import PHASES, MotionPlan, MotionSettings, plan_motion
from prg.sim.robots import RobotSettings
from prg.sim.scene import Camera, IKSettings, IKSolver, Scene

log = logging.getLogger(__name__)

__all__ = [
    "ControlSettings",
    "ReachMap",
    "SimResult",
    "SimSettings",
    "check_workspace",
    "simulate_word",
    "word_samples",
]


@dataclass(frozen=True)
class ControlSettings:
    """Physics and position control.

    Attributes
    ----------
    time_step : float
        Physics step (s); PyBullet's default is 1/240.
    steps_per_waypoint : int
        Physics steps between IK waypoints; joint targets are interpolated linearly in between
        (with the matching velocity as feed-forward).
    position_gain, velocity_gain : float
        PyBullet ``POSITION_CONTROL`` gains (``kp``, ``kd`` of its velocity-level motor
        constraint), at the URDF's joint force limits.
    contact_band_mm : float
        The pen tip inks while within this distance of the paper surface.
    settle_s : float
        Simulated time after the retreat, holding the home posture.
    """

    time_step: float = 1.0 / 240.0
    steps_per_waypoint: int = 4
    position_gain: float = 0.5
    velocity_gain: float = 1.0
    contact_band_mm: float = 0.5
    settle_s: float = 0.25

    def __post_init__(self) -> None:
        if not (math.isfinite(self.time_step) and 0 < self.time_step <= 0.05):
            raise UsageError(f"control.time_step must be in (0, 0.05] s, got {self.time_step!r}")
        if int(self.steps_per_waypoint) != self.steps_per_waypoint or self.steps_per_waypoint < 1:
            raise UsageError(
                f"control.steps_per_waypoint must be a positive integer, got "
                f"{self.steps_per_waypoint!r}"
            )
        for name in ("position_gain", "velocity_gain", "contact_band_mm"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise UsageError(f"control.{name} must be positive, got {getattr(self, name)!r}")
        if not (math.isfinite(self.settle_s) and self.settle_s >= 0):
            raise UsageError(f"control.settle_s must be >= 0, got {self.settle_s!r}")

    @property
    def waypoint_dt(self) -> float:
        """Time between IK waypoints (s)."""
        return self.time_step * self.steps_per_waypoint


@dataclass(frozen=True)
class SimSettings:
    """Everything :func:`simulate_word` needs besides the word and the robot.

    Attributes
    ----------
    paper : Paper
    motion : MotionSettings
    control : ControlSettings
    ik : IKSettings
    camera : Camera
        The page render.
    scale : float
        The word's size on the paper relative to its own (cm) size.
    word_centre_cm : tuple of float
        Where the centre of the word's bounding box goes, in the paper frame (cm).
    tempo : float
        Multiplies the DMP's duration (2: twice as slow).
    workspace_step_cm : float
        Grid spacing of the reachability map over the paper.
    """

    paper: Paper = field(default_factory=Paper)
    motion: MotionSettings = field(default_factory=MotionSettings)
    control: ControlSettings = field(default_factory=ControlSettings)
    ik: IKSettings = field(default_factory=IKSettings)
    camera: Camera = field(default_factory=Camera)
    scale: float = 1.0
    word_centre_cm: tuple[float, float] = (0.0, 0.0)
    tempo: float = 1.0
    workspace_step_cm: float = 1.0

    def __post_init__(self) -> None:
        for name in ("scale", "tempo", "workspace_step_cm"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise UsageError(f"{name} must be a positive number, got {getattr(self, name)!r}")
        centre = np.asarray(self.word_centre_cm, dtype=np.float64)
        if centre.shape != (2,) or not np.all(np.isfinite(centre)):
            raise UsageError(
                f"paper.word_centre_cm must be two numbers, got {self.word_centre_cm!r}"
            )


# ----------------------------------------------------------------------------- the word


MAX_WRITING_S = 600.0  # simulated seconds of writing (a 64-letter line takes about 140 s)


def _check_duration(word: WordTrajectory, seconds: float, tempo: float) -> None:
    if not seconds <= MAX_WRITING_S:
        raise UsageError(
            f"word {word.text[:40]!r} takes {seconds:.0f} s to write at tempo={tempo:g}: accepted "
            f"are at most {MAX_WRITING_S:.0f} s of writing; lower tempo or write fewer letters"
        )


def word_samples(
    word: WordTrajectory, dt: float, tempo: float = 1.0
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """The word's motion, sampled every ``dt`` seconds: its DMP rollout.

    Parameters
    ----------
    word : WordTrajectory
        With ``word.dmp`` (from ``prg-write``); without one, the points are followed at
        ``word.speed_cm_s`` with 0.3 s speed ramps.
    dt : float
        Sample spacing (s), about; the DMP's duration is divided evenly.
    tempo : float
        Multiplies the duration.

    Returns
    -------
    samples : ndarray, shape (n, 2)
        Centimetres, the word's own frame.
    t : ndarray, shape (n,)
        Seconds from 0.
    pen_down : ndarray of bool, shape (n,)
        False on the pen-up travel between words.
    """
    if word.dmp is not None:
        from prg.pipeline.dmp import DMP, rollout

        try:
            dmp = DMP.from_dict(word.dmp)
        except UsageError as err:
            raise UsageError(f"word {word.text!r}: invalid DMP ({err})") from None
        if dmp.dims != 2:
            raise UsageError(f"word {word.text!r}: the DMP must be 2-D, it has {dmp.dims} dims")
        tau = dmp.tau * tempo
        _check_duration(word, tau, tempo)
        samples = rollout(dmp, tau=tau, dt=dt)
    else:
        from prg.pipeline.timing import rest_to_rest_samples

        _check_duration(word, word.path_length / word.speed_cm_s * tempo, tempo)
        samples, tau = rest_to_rest_samples(word.points, word.speed_cm_s, 0.3, 1 / (dt * tempo))
        tau *= tempo
    t = np.linspace(0.0, tau, len(samples))
    down = pen_down_samples(word.points, word.segment, word.segment_kinds, samples)
    return samples, t, down


# ----------------------------------------------------------------------------- workspace


class ReachMap:
    """Which points of the paper the pen tip reaches, vertical, at the heights it needs.

    Grid nodes ``step_cm`` apart cover the sheet; a node is reachable when the IK (from the rest
    pose) puts the tip there within tolerance, inside the joint limits, at every height in
    ``heights_cm``. Nodes are solved on demand and remembered. A point counts as reachable when
    the four nodes of its grid cell are (a conservative rule: the reachable region is the union
    of fully reachable cells).

    Parameters
    ----------
    ik : IKSolver
    paper : Paper
    heights_cm : sequence of float
        Tip heights above the paper to check (the surface and the lift height).
    step_cm : float
    """

    def __init__(
        self, ik: IKSolver, paper: Paper, heights_cm: tuple[float, ...], step_cm: float
    ) -> None:
        self.ik, self.paper, self.heights = ik, paper, tuple(heights_cm)
        half = np.asarray(paper.size_cm) / 2
        self.nx = max(1, math.ceil(2 * half[0] / step_cm))
        self.ny = max(1, math.ceil(2 * half[1] / step_cm))
        self.xs = np.linspace(-half[0], half[0], self.nx + 1)
        self.ys = np.linspace(-half[1], half[1], self.ny + 1)
        self._nodes: dict[tuple[int, int], bool] = {}

    @property
    def solved(self) -> int:
        """Number of grid nodes solved so far."""
        return len(self._nodes)

    def node(self, i: int, j: int) -> bool:
        """Whether grid node ``(xs[i], ys[j])`` is reachable (solved once)."""
        key = (i, j)
        if key not in self._nodes:
            tol = self.ik.settings.tolerance_mm / 1000.0
            ok = True
            for h in self.heights:
                target = self.paper.to_world([[self.xs[i], self.ys[j], h]])[0]
                _, err = self.ik.solve(target)
                ok = ok and err <= tol
                if not ok:
                    break
            self._nodes[key] = ok
        return self._nodes[key]

    def reachable(
        self, points_cm: NDArray[np.float64], stop_early: bool = False
    ) -> NDArray[np.bool_]:
        """Whether each point ``(x, y)`` (paper frame, cm) is on the sheet and reachable.

        With ``stop_early``, cells are solved only until the first unreachable one; the points
        of cells not examined then are reported unreachable (use it for an all-or-nothing test).
        """
        pts = np.asarray(points_cm, dtype=np.float64)[:, :2]
        out = np.zeros(len(pts), dtype=bool)
        on = self.paper.contains(pts)
        if stop_early and not on.all():
            return out
        i = np.clip(np.searchsorted(self.xs, pts[:, 0], side="right") - 1, 0, self.nx - 1)
        j = np.clip(np.searchsorted(self.ys, pts[:, 1], side="right") - 1, 0, self.ny - 1)
        cells, which = np.unique(np.column_stack([i, j])[on], axis=0, return_inverse=True)
        ok = np.zeros(len(cells), dtype=bool)
        for c, (a, b) in enumerate(cells.tolist()):
            ok[c] = all(self.node(a + da, b + db) for da in (0, 1) for db in (0, 1))
            if stop_early and not ok[c]:
                return out
        out[on] = ok[which.reshape(-1)]
        return out


def check_workspace(
    points_cm: NDArray[np.float64],
    anchor: NDArray[np.float64],
    target: NDArray[np.float64],
    scale: float,
    reach: ReachMap,
    robot: str,
    text: str,
) -> None:
    """Refuse a word that does not fit the reachable workspace on the paper.

    Parameters
    ----------
    points_cm : ndarray, shape (n, 2)
        The word's motion in its own frame (cm, unscaled).
    anchor, target : ndarray, shape (2,)
        The word's anchor (centre of its bounding box) and where it goes on the paper.
    scale : float
        The requested scale.
    reach : ReachMap
    robot, text : str
        For the message.

    Raises
    ------
    UsageError
        One line: the word's size, the largest size that fits (found by bisection on the scale
        about the same centre) and the ``scale=`` to set.
    """
    placed = place_points(points_cm, anchor, scale, target)
    ok = reach.reachable(placed)
    if ok.all():
        return

    def fits(s: float) -> bool:
        return bool(reach.reachable(place_points(points_cm, anchor, s, target), True).all())

    lo, hi = 0.0, scale
    for _ in range(14):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if fits(mid) else (lo, mid)
    low, high = bounding_box(points_cm)
    width, height = (high - low) * scale
    bad = placed[~ok][0]
    where = "off the paper" if not reach.paper.contains(bad[None])[0] else "out of reach"
    if lo <= 0:
        raise UsageError(
            f"word {text!r} cannot be written by {robot} at paper.word_centre_cm="
            f"[{target[0]:g},{target[1]:g}]: that point is {where}; move the word"
        )
    factor = math.floor(lo * 1000) / 1000
    raise UsageError(
        f"word {text!r} is {width:.1f} cm wide and {height:.1f} cm tall at scale={scale:g}, "
        f"and ({bad[0]:.1f}, {bad[1]:.1f}) cm on the paper is {where}; at most "
        f"{width * lo / scale:.1f} cm wide fits {robot}'s workspace on the "
        f"{reach.paper.size_cm[0]:g} x {reach.paper.size_cm[1]:g} cm paper: set "
        f"scale={factor:g} or smaller"
    )


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


def _describe(plan: MotionPlan):
    def describe(i: int) -> str:
        x, y, h = plan.tip[i]
        return (
            f"({x:.1f}, {y:.1f}) cm on the paper, {h:.1f} cm above it "
            f"({PHASES[plan.phase[i]]} at t = {plan.t[i]:.2f} s)"
        )

    return describe


def simulate_word(
    word: WordTrajectory,
    robot: RobotSettings,
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
    robot : RobotSettings
    settings : SimSettings, optional
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
    s = settings or SimSettings()
    ctl = s.control
    dt = ctl.waypoint_dt
    samples, t_word, down = word_samples(word, dt, s.tempo)
    low, high = bounding_box(samples)
    anchor = (low + high) / 2
    centre = np.asarray(s.word_centre_cm, dtype=np.float64)
    placed = place_points(samples, anchor, s.scale, centre)
    width, height = (high - low) * s.scale
    start = time.perf_counter()
    with IKSolver(robot, s.ik) as ik:
        reach = ReachMap(ik, s.paper, (0.0, s.motion.lift_cm), s.workspace_step_cm)
        check_workspace(samples, anchor, centre, s.scale, reach, robot.name, word.text)
        home = s.paper.to_paper(ik.tip(ik.robot.rest_movable))[0]
        plan = plan_motion(placed, t_word, down, home, s.motion, dt)
        bar = _progress(len(plan.t), f"{robot.name}: inverse kinematics", progress, "waypoint")
        try:
            q_plan, ik_err = ik.solve_path(
                s.paper.to_world(plan.tip),
                describe=_describe(plan),
                progress=None if bar is None else bar.update,
            )
        finally:
            if bar is not None:
                bar.close()
        log.info(
            "IK: %d waypoints (%d workspace nodes) in %.2f s, tip error mean %.4f max %.4f mm",
            len(plan.t),
            reach.solved,
            time.perf_counter() - start,
            ik_err.mean() * 1000,
            ik_err.max() * 1000,
        )
    ik_wall = time.perf_counter() - start

    n_steps = math.ceil((plan.duration_s + ctl.settle_s) / ctl.time_step)
    t = (np.arange(n_steps) + 1) * ctl.time_step
    targets = np.column_stack([np.interp(t, plan.t, q_plan[:, j]) for j in range(q_plan.shape[1])])
    # piecewise-linear targets: the velocity of the interval each step falls in
    interval = np.clip(np.searchsorted(plan.t, t, side="right") - 1, 0, len(plan.t) - 2)
    velocities = (q_plan[interval + 1] - q_plan[interval]) / np.diff(plan.t)[interval][:, None]
    velocities[t >= plan.t[-1]] = 0.0
    commanded = np.column_stack([np.interp(t, plan.t, plan.tip[:, d]) for d in range(3)])
    step_stroke = plan.stroke[np.clip(np.searchsorted(plan.t, t, side="left"), 0, len(plan.t) - 1)]

    with Scene(robot, s.paper, gui=gui, time_step=ctl.time_step) as scene:
        scene.reset(q_plan[0])
        arm = list(scene.robot.arm_in_movable)
        q = np.empty((n_steps, len(arm)))
        tip = np.empty((n_steps, 3))
        orn = np.empty((n_steps, 4))
        bar = _progress(n_steps, f"{robot.name} writes {word.text!r}", progress, "step")
        start = time.perf_counter()
        for i in range(n_steps):
            scene.command(targets[i], velocities[i], ctl.position_gain, ctl.velocity_gain)
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
            bar.close()
        tip_paper = s.paper.to_paper(tip)
        contact = in_contact(tip_paper[:, 2], ctl.contact_band_mm)
        result = SimResult(
            text=word.text,
            robot=robot,
            settings=s,
            plan=plan,
            q_plan=q_plan,
            ik_error_m=ik_err,
            t=t,
            q=q,
            q_target=targets[:, arm],
            tip_world=tip,
            tip_quaternion=orn,
            tip_paper=tip_paper,
            commanded=commanded,
            contact=contact,
            step_stroke=step_stroke,
            placement={
                "anchor_cm": anchor.tolist(),
                "centre_cm": centre.tolist(),
                "scale": s.scale,
                "width_cm": float(width),
                "height_cm": float(height),
            },
            wall_s=wall,
            ik_wall_s=ik_wall,
        )
        if render:
            from prg.sim.ink import page_texture

            scene.show_ink(page_texture(result.ink_strokes(), s.paper))
            result.page = scene.render(
                s.camera,
                target=s.paper.to_world(centre[None])[0],
                extent_m=(high - low) * s.scale / 100.0,
            )
    m = result.metrics
    log.info(
        "%s wrote %r: tracking error mean %.3f mm, max %.3f mm; longest ink gap %.3f mm "
        "(pen step %.3f mm); %.1f s simulated in %.1f s",
        robot.name,
        word.text,
        m["tracking_error_mean_mm"],
        m["tracking_error_max_mm"],
        m["max_ink_gap_mm"],
        m["pen_step_mm"],
        m["sim_s"],
        m["wall_s"] + m["ik_wall_s"],
    )
    return result


def _progress(total: int, description: str, enabled: bool, unit: str):
    if not enabled:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=description, unit=unit, leave=False)
