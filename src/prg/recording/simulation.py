"""Rerun recording (``sim.rrd``) of the simulated robot writing a word.

Written through :func:`~prg.recording.stream.recording_stream` (explicit stream, atomic file)
on one duration timeline, ``sim_time`` (simulated seconds). Entity paths:

==================================  ====================  =========================================
entity                              archetype             when
==================================  ====================  =========================================
``world``                           ViewCoordinates       static: right-handed, z up (metres)
``world/table``, ``world/paper``    Boxes3D               static
``world/<arm>/...``                 URDF (Rerun import)   static: link meshes, frames, joints at 0
``world/<arm>/base``                Transform3D           static: ``tf#/world`` -> the URDF's root
``world/<arm>/joints/<joint>``      Transform3D           per frame, one ``send_columns`` per joint
``world/pen/body``                  Cylinders3D           static, in the flange link's frame
``world/commanded``                 LineStrips3D          static: the commanded pen-down strokes
``world/pen/tip``                   Points3D              per frame
``world/pen/path``                  LineStrips3D          one segment per frame (the tip's path)
``world/ink``                       LineStrips3D          one segment per inked physics step
``page/commanded``                  LineStrips2D          static (paper frame, cm, y flipped)
``page/ink``                        LineStrips2D          one segment per inked physics step
``page/pen``                        Points2D              per frame (the tip over the page)
``page_render``                     EncodedImage          static: the TinyRenderer page picture
``joints/<joint>``                  Scalars               per frame (rad)
``summary``                         TextDocument          static: the metrics
==================================  ====================  =========================================

The arm is Rerun's own URDF import (:class:`rerun.urdf.UrdfTree`) of the same URDF PyBullet
loads (collision geometry left out, ``package://`` mesh paths made absolute). Since Rerun 0.28
URDF links are *named transform frames*: the import logs every link's geometry with a
:class:`rerun.CoordinateFrame` and every joint (at 0) as a static ``Transform3D`` between its
parent and child link frames under ``world/<arm>/tf_static``; the animation sends, per revolute
joint, its transform at each frame's joint angle
(:meth:`rerun.urdf.UrdfJoint.compute_transform_columns`) on ``world/<arm>/joints/<joint>``, and
one static transform places the URDF's root link at the robot's base pose in ``tf#/world``.
``<arm>`` is the URDF's robot name (``panda``, ``lbr_iiwa``).

*Frames* are every ``every``-th physics step (the IK waypoint rate by default); the ink is logged
at every physics step. Growing paths (ink, tip path) are one two-point segment per row, shown
accumulated by the default blueprint with a visible time range from the start to the cursor
(:mod:`prg.recording.views`): the data grow linearly with the steps.
"""

from __future__ import annotations

import io
import itertools
import logging
import os
import tempfile
import time
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from prg.plotting import (
    COMMANDED,
    INK,
    PAPER,
    PEN,
    PEN_BODY,
    PEN_TRACE,
    SCENE,
    SHEET,
    TABLE,
)
from prg.recording.stream import recording_stream
from prg.recording.views import (
    accumulated,
    flip,
    framing,
    framing_eye,
    log_columns,
    segments,
)

if TYPE_CHECKING:  # prg.sim imports this module: nothing of prg.sim at import time
    from prg.sim.robots import RobotSettings
    from prg.sim.writing import SimResult

log = logging.getLogger("prg.recording")

SIM_TIMELINE = "sim_time"
PEN_BODY_ENTITY = "world/pen/body"
LIFT_M = 0.0002  # draw paths this far over the paper so they are not hidden in it
# where the 3D views look from, in the page's axes (writing line, up the page, up)
ROBOT_VIEW_FROM = np.array([0.8, -1.0, 1.2])  # behind the robot's right shoulder
PEN_VIEW_FROM = np.array([0.25, -0.6, 1.0])  # from the robot's side, steeply down on the word
VIEW_ASPECT = 1.5  # the 3D views are at least this much wider than tall on a landscape screen
LEGEND_ROOM = 0.3  # the joint plot's time axis runs on this fraction past the motion


def recording_urdf(robot: RobotSettings, folder: str | os.PathLike) -> Path:
    """A copy of the robot's URDF for Rerun's importer: visual geometry only, mesh paths
    absolute (``package://`` and relative paths resolved against the URDF's folder).

    Returns
    -------
    Path
        ``<folder>/<robot>.urdf``.
    """
    source = robot.urdf_path
    tree = ET.parse(source)
    root = tree.getroot()
    for link in root.iter("link"):
        for collision in link.findall("collision"):
            link.remove(collision)
    for mesh in root.iter("mesh"):
        name = mesh.get("filename", "")
        if name.startswith("package://"):
            name = name[len("package://") :]
        if not Path(name).is_absolute():
            name = str((source.parent / name).resolve())
        mesh.set("filename", name)
    out = Path(folder) / f"{robot.name}.urdf"
    tree.write(out)
    return out


def _ink_segments(points: np.ndarray, keep: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Indices ``i`` of the rows ``(points[i - 1], points[i])`` joining two kept samples of one
    run, and the segments themselves, shape (k, 2, dims)."""
    from prg.sim.geometry import runs

    rows = [np.arange(a + 1, b) for a, b in runs(keep)]
    idx = np.concatenate(rows) if rows else np.empty(0, dtype=int)
    return idx, np.stack([points[idx - 1], points[idx]], axis=1)


def _pen_geometry(robot: RobotSettings) -> rr.Cylinders3D:
    offset = np.asarray(robot.pen_offset, dtype=np.float64)
    axis = offset / np.linalg.norm(offset)
    centre = offset - axis * robot.pen_length / 2
    z = np.array([0.0, 0.0, 1.0])
    cross = np.cross(z, axis)
    if np.linalg.norm(cross) < 1e-12:
        quat = [0.0, 0.0, 0.0, 1.0] if axis[2] > 0 else [1.0, 0.0, 0.0, 0.0]
    else:
        half = np.arccos(np.clip(axis @ z, -1, 1)) / 2
        quat = [*(cross / np.linalg.norm(cross) * np.sin(half)), np.cos(half)]
    return rr.Cylinders3D(
        lengths=[robot.pen_length],
        radii=[robot.pen_radius],
        centers=[centre],
        quaternions=[rr.Quaternion(xyzw=quat)],
        colors=[PEN_BODY],
        fill_mode="solid",
    )


def _arm_points(result: SimResult, frames: int = 24) -> np.ndarray:
    """Corners of the bounding box of every link of the arm at ``frames`` moments of the
    motion (PyBullet's, at the recorded joint angles), world metres, shape (n, 3)."""
    from prg.sim.scene import Scene

    steps = np.unique(np.linspace(0, len(result.q) - 1, frames).round().astype(int))
    corners = []
    with Scene(result.robot, result.settings.paper) as scene:
        p, body, cid = scene.p, scene.robot.body, scene.cid
        links = range(-1, p.getNumJoints(body, physicsClientId=cid))
        for step in steps:
            for joint, q in zip(scene.robot.arm, result.q[step]):
                p.resetJointState(body, joint, float(q), physicsClientId=cid)
            for link in links:
                low, high = p.getAABB(body, link, physicsClientId=cid)
                corners.extend(itertools.product(*zip(low, high)))
    return np.asarray(corners)


def _page_corners(result: SimResult) -> np.ndarray:
    half_w, half_h = np.asarray(result.settings.paper.size_cm) / 2
    corners = [[-half_w, -half_h], [half_w, -half_h], [half_w, half_h], [-half_w, half_h]]
    return result.settings.paper.to_world(corners)


def sim_blueprint(result: SimResult) -> rrb.Blueprint:
    """The default layout, every view framed on its data.

    *Robot*: the arm over its whole motion and the page, seen from behind the robot's right
    shoulder (the word reads left to right; at this distance it is a few pixels). *Pen on the
    page*: the written word filling the view, seen from the robot's side, with the pen coming
    down on it (a wireframe there, so that it hides no ink). Beside them the page in 2D (ink over
    the commanded strokes) with its TinyRenderer picture in a tab, the joint angles (the time
    axis runs on past the motion, so that the legend sits beside the curves, not over them) and
    the metrics. The side panels start collapsed, the time panel as its playback bar.
    """
    paper = result.settings.paper
    axes = paper.rotation  # columns: the page's x (writing line), y (up the page), z (up)
    strokes = result.plan.strokes()
    word = paper.to_world(np.concatenate(strokes))
    trails = {
        "world/ink": accumulated(SIM_TIMELINE, rr.LineStrips3D),
        "world/pen/path": accumulated(SIM_TIMELINE, rr.LineStrips3D),
    }
    robot = rrb.Spatial3DView(
        origin="world",
        name=f"{result.robot.name} writes {result.text!r}",
        background=SCENE,
        eye_controls=framing_eye(
            np.concatenate([_arm_points(result), _page_corners(result)]),
            axes @ ROBOT_VIEW_FROM,
            margin=0.05,
            aspect=VIEW_ASPECT,
        ),
        overrides=trails,
    )
    see_through_pen = rr.Cylinders3D.from_fields(fill_mode=rr.components.FillMode.MajorWireframe)
    close_up = rrb.Spatial3DView(
        origin="world",
        name="Pen on the page",
        background=SCENE,
        eye_controls=framing_eye(word, axes @ PEN_VIEW_FROM, margin=0.3, aspect=VIEW_ASPECT),
        overrides={**trails, PEN_BODY_ENTITY: see_through_pen.visualizer()},
    )
    page = rrb.Spatial2DView(
        origin="page",
        name="Ink on the page (cm)",
        background=PAPER,
        visual_bounds=framing(flip(np.concatenate(strokes))),
        overrides={"page/ink": accumulated(SIM_TIMELINE)},
    )
    if result.page is not None:
        render = rrb.Spatial2DView(origin="page_render", name="Page render (TinyRenderer)")
        page = rrb.Tabs(page, render)
    end_s = float(result.t[-1])
    joints = rrb.TimeSeriesView(
        origin="joints",
        name="Joint angles (rad)",
        axis_x=rrb.TimeAxis(
            link=rrb.components.LinkAxis.Independent,
            view_range=rrb.TimeRange(
                start=rrb.TimeRangeBoundary.absolute(seconds=0.0),
                end=rrb.TimeRangeBoundary.absolute(seconds=end_s * (1.0 + LEGEND_ROOM)),
            ),
        ),
        plot_legend=rrb.PlotLegend(corner=rrb.Corner2D.RightTop, visible=True),
    )
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(robot, joints, row_shares=[3, 2]),
            rrb.Vertical(
                close_up,
                page,
                rrb.TextDocumentView(origin="summary", name="Summary"),
                row_shares=[3, 2, 2],
            ),
            column_shares=[3, 2],
        ),
        rrb.TimePanel(timeline=SIM_TIMELINE, state="collapsed"),
        collapse_panels=True,
    )


def _summary(result: SimResult) -> str:
    m = result.metrics
    return "\n".join(
        [
            f"# {result.robot.name} writes {result.text!r}",
            "",
            f"- tracking error: mean {m['tracking_error_mean_mm']:.4f} mm, "
            f"max {m['tracking_error_max_mm']:.4f} mm",
            f"- longest ink gap: {m['max_ink_gap_mm']:.3f} mm (pen step {m['pen_step_mm']:.3f} mm)",
            f"- word: {m['word_width_cm']:.2f} x {m['word_height_cm']:.2f} cm "
            f"(scale {m['scale']:g}); {m['ink_strokes']} ink strokes",
            f"- simulated {m['sim_s']:.2f} s in {m['wall_s'] + m['ik_wall_s']:.2f} s wall "
            f"(real-time factor {m['realtime_factor']:.1f})",
            "- coordinates: world in metres (z up); page in cm, logged as (x, -y)",
        ]
    )


def record_simulation(
    path: str | os.PathLike,
    result: SimResult,
    *,
    every: int | None = None,
    application_id: str = "prg-simulate",
) -> Path:
    """Record the simulation to an ``.rrd`` file, atomically (entities in the module docstring).

    Parameters
    ----------
    path : path-like
    result : SimResult
    every : int, optional
        Log the arm, the pen tip and the joint angles every ``every`` physics steps (default:
        ``steps_per_waypoint``); the ink is logged at every step.
    application_id : str

    Returns
    -------
    Path
    """
    from rerun.urdf import UrdfTree

    from prg.sim.scene import TABLE_TOP_Z

    start = time.perf_counter()
    robot = result.robot
    paper = result.settings.paper
    every = every or result.settings.control.steps_per_waypoint
    frames = np.arange(every - 1, len(result.t), every)
    if frames[-1] != len(result.t) - 1:
        frames = np.append(frames, len(result.t) - 1)
    t_frames = result.t[frames]
    lift = np.array([0.0, 0.0, LIFT_M])
    with (
        tempfile.TemporaryDirectory(prefix="prg-urdf-") as tmp,
        recording_stream(path, application_id, blueprint=sim_blueprint(result)) as rec,
    ):
        rec.log(
            "summary", rr.TextDocument(_summary(result), media_type="text/markdown"), static=True
        )
        rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        rec.log(
            "world/table",
            rr.Boxes3D(
                centers=[[paper.centre[0], 0.0, TABLE_TOP_Z - 0.025]],
                half_sizes=[[0.75, 0.5, 0.025]],
                colors=[TABLE],
                fill_mode="solid",
            ),
            static=True,
        )
        rec.log(
            "world/paper",
            rr.Boxes3D(
                centers=[np.asarray(paper.centre) - [0.0, 0.0, paper.thickness_m / 2]],
                half_sizes=[
                    [paper.size_cm[0] / 200, paper.size_cm[1] / 200, paper.thickness_m / 2]
                ],
                quaternions=[rr.Quaternion(xyzw=paper.quaternion)],
                colors=[SHEET],
                fill_mode="solid",
            ),
            static=True,
        )

        # the arm: URDF once, its root at the base pose, each revolute joint animated
        urdf = recording_urdf(robot, tmp)
        arm = f"world/{UrdfTree.from_file_path(urdf).name}"
        tree = UrdfTree.from_file_path(
            urdf, entity_path_prefix="world", static_transform_entity_path=f"{arm}/tf_static"
        )
        tree.log_urdf_to_recording(rec)
        rec.log(
            f"{arm}/base",
            rr.Transform3D(
                translation=robot.base_position,
                quaternion=rr.Quaternion(xyzw=robot.base_quaternion),
                parent_frame="tf#/world",
                child_frame=tree.root_link().name,
            ),
            static=True,
        )
        times = [rr.TimeColumn(SIM_TIMELINE, duration=t_frames)]
        for j, name in enumerate(robot.arm_joints):
            joint = tree.get_joint_by_name(name)
            rec.send_columns(
                f"{arm}/joints/{name}",
                indexes=times,
                columns=joint.compute_transform_columns(result.q[frames, j], clamp=False),
            )
            rec.send_columns(
                f"joints/{name}",
                indexes=times,
                columns=rr.Scalars.columns(scalars=result.q[frames, j]),
            )
        rec.log(
            PEN_BODY_ENTITY,
            rr.CoordinateFrame(robot.flange_link),
            _pen_geometry(robot),
            static=True,
        )

        # the commanded strokes, the pen tip, its path and the ink
        commanded = result.plan.strokes()
        rec.log(
            "world/commanded",
            rr.LineStrips3D(
                [paper.to_world(np.column_stack([c, np.zeros(len(c))])) + lift for c in commanded],
                colors=[COMMANDED],
                radii=rr.Radius.ui_points(1.0),
            ),
            static=True,
        )
        rec.log(
            "page/commanded",
            rr.LineStrips2D(
                [flip(c) for c in commanded],
                colors=[COMMANDED],
                radii=rr.Radius.ui_points(3.0),
                draw_order=1.0,
            ),
            static=True,
        )
        tip = result.tip_world[frames]
        log_columns(
            rec,
            "world/pen/tip",
            rr.Points3D.from_fields(colors=[PEN], radii=[0.002]),
            SIM_TIMELINE,
            t_frames,
            rr.Points3D.columns(positions=tip),
        )
        log_columns(
            rec,
            "world/pen/path",
            rr.LineStrips3D.from_fields(colors=[PEN_TRACE], radii=rr.Radius.ui_points(1.0)),
            SIM_TIMELINE,
            t_frames[1:],
            rr.LineStrips3D.columns(strips=segments(tip)),
        )
        log_columns(
            rec,
            "page/pen",
            rr.Points2D.from_fields(colors=[PEN], radii=rr.Radius.ui_points(6.0), draw_order=30.0),
            SIM_TIMELINE,
            t_frames,
            rr.Points2D.columns(positions=flip(result.tip_paper[frames, :2])),
        )
        rows, ink3d = _ink_segments(result.tip_world + lift, result.contact)
        _, ink2d = _ink_segments(flip(result.tip_paper[:, :2]), result.contact)
        log_columns(
            rec,
            "world/ink",
            rr.LineStrips3D.from_fields(colors=[INK], radii=rr.Radius.ui_points(2.0)),
            SIM_TIMELINE,
            result.t[rows],
            rr.LineStrips3D.columns(strips=ink3d),
        )
        log_columns(
            rec,
            "page/ink",
            rr.LineStrips2D.from_fields(
                colors=[INK], radii=rr.Radius.ui_points(2.0), draw_order=20.0
            ),
            SIM_TIMELINE,
            result.t[rows],
            rr.LineStrips2D.columns(strips=ink2d),
        )
        if result.page is not None:
            from PIL import Image

            buffer = io.BytesIO()
            Image.fromarray(result.page).save(buffer, format="PNG")
            rec.log(
                "page_render",
                rr.EncodedImage(contents=buffer.getvalue(), media_type="image/png"),
                static=True,
            )
    log.info(
        "recorded %s writing %r to %s in %.2f s (%d frames, %d ink segments)",
        robot.name,
        result.text,
        path,
        time.perf_counter() - start,
        len(frames),
        len(rows),
    )
    return Path(path)
