"""Tests of ``prg.export.plotter`` (moved from the suite on: a written word exported to real
machines (prg.export, prg-export): every file is read back with another reader (gcodeparser, an
HPGL parser written here, vpype's SVG reader, mcap-ros2's reader, numpy) and compared with what
the word, its DMP timing and the simulated arm say independently; the joint-limit check slows a
too-fast timing by the smallest factor and refuses what no slow-down fixes)."""

from __future__ import annotations

import re

import numpy as np
import pytest
from numpy.testing import assert_allclose

from prg.errors import SettingsError
from prg.export import (
    GcodeSettings,
    PlotterSettings,
)
from prg.export.plotter import gcode_text, place_word, timed_strokes
from tests.helpers.export import DT, _nearest, _timed, parse_gcode, word  # noqa: F401 (fixtures)

# ----------------------------------------------------------------------------- G-code


def test_gcode_follows_the_timed_word_within_a_hundredth_of_a_millimetre_and_its_time(word):
    runs, pen_down_s = _timed(word)
    placement = place_word(word, PlotterSettings())
    program = gcode_text(timed_strokes(word, placement, DT), PlotterSettings(), GcodeSettings())
    strokes, seconds = parse_gcode(program.text)
    assert len(strokes) == len(runs) >= 2  # two words (and the i's dot)
    for parsed, expected in zip(strokes, runs):
        assert _nearest(parsed, expected).max() < 0.01
        assert _nearest(expected, parsed).max() < 0.01
        assert_allclose(parsed[[0, -1]], expected[[0, -1]], atol=0.001)
    assert seconds == pytest.approx(pen_down_s, rel=1e-3)
    assert program.pen_down_s == pytest.approx(seconds, rel=1e-6)
    header = program.text.splitlines()[:5]
    assert {"G21", "G90"} <= {line.split()[0] for line in header}


def test_gcode_in_inches_is_the_same_path_and_time(word):
    runs, pen_down_s = _timed(word)
    placement = place_word(word, PlotterSettings())
    settings = GcodeSettings(units="inch", decimals=5, z_up_mm=5.08)
    program = gcode_text(timed_strokes(word, placement, DT), PlotterSettings(), settings)
    strokes, seconds = parse_gcode(program.text)
    assert len(strokes) == len(runs)
    for parsed, expected in zip(strokes, runs):
        assert _nearest(parsed * 25.4, expected).max() < 0.01  # inches back to mm
    assert seconds == pytest.approx(pen_down_s, rel=1e-3)
    lines = program.text.splitlines()
    assert lines[1].startswith("G20") and "G0 Z0.20000" in lines
    with pytest.raises(SettingsError, match="units"):
        GcodeSettings(units="cm")


def test_gcode_at_half_the_tempo_takes_twice_as_long(word):
    placement = place_word(word, PlotterSettings())
    fast = gcode_text(timed_strokes(word, placement, DT, 1.0), PlotterSettings(), GcodeSettings())
    slow = gcode_text(timed_strokes(word, placement, DT, 2.0), PlotterSettings(), GcodeSettings())
    (fast_strokes, fast_s), (slow_strokes, slow_s) = parse_gcode(fast.text), parse_gcode(slow.text)
    assert len(slow_strokes) == len(fast_strokes)
    assert slow_s == pytest.approx(_timed(word, tempo=2.0)[1], rel=1e-3)
    # twice as long, but for where the pen-down runs end: each rollout's own samples decide it
    assert slow_s == pytest.approx(2 * fast_s, rel=1e-2)


def test_servo_pen_and_origin_offset_move_the_program_not_the_timing(word):
    runs, pen_down_s = _timed(word)
    placement = place_word(word, PlotterSettings())
    settings = GcodeSettings(
        pen="servo", servo_down="M3 S90", servo_up="M5", servo_wait_s=0.3, origin_mm=(100, -20)
    )
    program = gcode_text(timed_strokes(word, placement, DT), PlotterSettings(), settings)
    strokes, seconds = parse_gcode(program.text)
    assert len(strokes) == len(runs)
    for parsed, expected in zip(strokes, runs):
        assert _nearest(parsed, expected + np.array([100.0, -20.0])).max() < 0.01
    assert seconds == pytest.approx(pen_down_s, rel=1e-3)
    lines = program.text.splitlines()
    assert not [line for line in lines if re.match(r"G[01] .*Z", line)]  # no Z moves
    assert lines.count("M3 S90") == len(runs) and lines.count("G4 P0.300") == 2 * len(runs) + 1
