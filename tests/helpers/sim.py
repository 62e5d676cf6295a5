"""Helpers shared by the tests that were split out of tests/test_sim.py."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from prg.recording.simulation import record_simulation
from prg.sim import (
    RobotSettings,
    SimSettings,
    font_word,
    simulate_word,
)


def _config(robot: str = "panda", **changes):
    """A robot of conf/robot/ and the settings of conf/simulate.yaml (the library defaults),
    with ``changes``."""
    return RobotSettings.named(robot), replace(SimSettings(), **changes)


@pytest.fixture(scope="module")
def panda_hi():
    """'hi' written by the Panda with the default settings of conf/simulate.yaml: the word in one
    stroke, then the i's dot."""
    robot, settings = _config()
    return simulate_word(font_word("hi"), robot, settings)


@pytest.fixture(scope="module")
def recording(panda_hi, tmp_path_factory) -> Path:
    return record_simulation(tmp_path_factory.mktemp("rrd") / "sim.rrd", panda_hi)
