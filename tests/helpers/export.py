"""Helpers shared by the tests that were split out of tests/test_export.py."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from prg.commands.cli import compose_config
from prg.export import (
    JointLimits,
)
from prg.sim import font_word, simulate_word, word_samples

DT = 0.01  # s, the G-code's sample spacing in these tests


A4 = (297.0, 210.0)


PANDA_ARM = slice(0, 7)  # panda.urdf's movable joints: panda_joint1..7, then the two fingers


# ----------------------------------------------------------------------------- fixtures


@pytest.fixture(scope="module")
def word():
    return font_word("h i")


@pytest.fixture(scope="module")
def panda_datasheet():
    """The Panda's datasheet limits as conf/export.yaml gives them."""
    from omegaconf import OmegaConf

    from prg.sim import RobotSettings

    node = OmegaConf.to_container(compose_config("export", []).limits.joints.panda)
    return JointLimits.from_mapping(RobotSettings.named("panda").arm_joints, node)


@pytest.fixture(scope="module")
def written(word):
    """The Panda writes "h i" at the DMP's own tempo."""
    return simulate_word(word, "panda", render=False)


# ----------------------------------------------------------------------------- expectations


def _ink_pieces(word) -> list[np.ndarray]:
    return [np.asarray(p) for _, p in word.polylines(highlight=False)]


def _centred(word, paper=A4, scale=1.0):
    """Word cm -> sheet mm for a word centred on the sheet (the default placement)."""
    ink = np.concatenate(_ink_pieces(word))
    middle = (ink.min(axis=0) + ink.max(axis=0)) / 2
    return lambda pts: np.asarray(paper) / 2 + 10.0 * scale * (np.asarray(pts) - middle)


def _timed(word, tempo=1.0):
    """The word's timed pen-down runs (sheet mm) and its pen-down time, from word_samples."""
    samples, t, down = word_samples(word, DT, tempo)
    place = _centred(word)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], down.astype(int), [0]])))
    runs = [place(samples[a:b]) for a, b in zip(edges[::2], edges[1::2])]
    both = down[1:] & down[:-1]
    return runs, float(np.diff(t)[both].sum())


def _nearest(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from each point of ``a`` to the nearest point of ``b``."""
    from scipy.spatial import cKDTree

    return cKDTree(b).query(a)[0]


# ----------------------------------------------------------------------------- readers


def parse_gcode(text: str, z_down: float = 0.0, servo_down: str = "M3", servo_up: str = "M5"):
    """Pen-down polylines (mm) and pen-down time (s) of a G-code program, read with gcodeparser:
    the pen is down after a Z move to ``z_down`` or a ``servo_down`` command; the time is the
    G1 moves' distance / feed and the G4 dwells while down, but the wait right after a servo
    command (the pen settling)."""
    from gcodeparser import parse_gcode_lines

    pos, feed, down, settling = np.zeros(2), None, False, False
    strokes, seconds = [], 0.0
    for line in parse_gcode_lines(text):
        cmd, params = line.command_str, line.params
        if cmd in (servo_down, servo_up):
            down = cmd == servo_down
            if down:
                strokes.append([pos.copy()])
            settling = True
            continue
        if cmd == "G4":
            if down and not settling:
                seconds += float(params["P"])
            settling = False
            continue
        settling = False
        if cmd not in ("G0", "G1"):
            continue
        feed = params.get("F", feed)
        if "Z" in params:
            now_down = params["Z"] <= z_down + 1e-9
            if now_down and not down:
                strokes.append([pos.copy()])
            down = now_down
        if "X" in params or "Y" in params:
            new = np.array([params.get("X", pos[0]), params.get("Y", pos[1])], dtype=float)
            if down:
                assert cmd == "G1", "a rapid move with the pen down"
                seconds += float(np.linalg.norm(new - pos)) / feed * 60.0
                strokes[-1].append(new)
            pos = new
    return [np.array(s) for s in strokes], seconds


def read_mcap(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # the module's own import warning
        from mcap_ros2.reader import read_ros2_messages
    return {m.channel.topic: m for m in read_ros2_messages(str(path))}
