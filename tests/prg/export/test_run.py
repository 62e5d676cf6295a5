"""Tests of ``prg.export.run`` (moved from the suite on: a written word exported to real machines
(prg.export, prg-export): every file is read back with another reader (gcodeparser, an HPGL
parser written here, vpype's SVG reader, mcap-ros2's reader, numpy) and compared with what the
word, its DMP timing and the simulated arm say independently; the joint-limit check slows a too-
fast timing by the smallest factor and refuses what no slow-down fixes)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from numpy.testing import assert_allclose

from prg.errors import UsageError
from prg.export import (
    ExportSettings,
    GcodeSettings,
    HpglSettings,
    PlotterSettings,
    export_word,
)
from prg.export.plotter import gcode_text, place_word, timed_strokes
from tests.helpers.export import A4, DT, _centred, _ink_pieces, _nearest, word  # noqa: F401 (fixtures)


def _length(polylines) -> float:
    return sum(float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()) for p in polylines)


def parse_hpgl(text: str, device: str = "hp7475a", page: str = "a4", paper=A4):
    """Pen-down polylines of HPGL (PU/PD/PA/PR, integer plotter units), in sheet mm (y up from
    the lower-left corner): the device's unit length and origin from vpype's profile, its y
    axis up."""
    import vpype as vp

    mm = vp.convert_length("mm")
    config = vp.config_manager.get_plotter_config(device)
    paper_config = config.paper_config(page)
    unit = config.plotter_unit_length / mm
    ox, oy = (v / mm for v in paper_config.origin_location)
    assert paper_config.y_axis_up and paper_config.origin_location_reference == "topleft"
    pos, down, relative, strokes = np.zeros(2), False, False, []
    for token in filter(None, (t.strip() for t in text.split(";"))):
        op, args = token[:2], token[2:]
        numbers = [int(v) for v in args.split(",")] if args else []
        if op == "PA":
            relative = False
        elif op == "PR":
            relative = True
        elif op in ("PU", "PD"):
            down = op == "PD"
            for x, y in zip(numbers[::2], numbers[1::2]):
                pos = pos + np.array([x, y]) if relative else np.array([x, y])
                if down:
                    strokes[-1].append(pos.copy())
                else:
                    strokes.append([pos.copy()])
    out = []
    for stroke in strokes:
        if len(stroke) < 2:
            continue
        pu = np.array(stroke, dtype=float)
        out.append(np.column_stack([ox + pu[:, 0] * unit, paper[1] - (oy - pu[:, 1] * unit)]))
    return out, unit


def test_a_word_off_the_sheet_or_too_fast_or_without_a_dmp_is_refused(word):
    placement = place_word(word, PlotterSettings(scale=30.0))
    with pytest.raises(UsageError, match=r"does not fit the 297 x 210 mm paper"):
        gcode_text(timed_strokes(word, placement, DT), PlotterSettings(scale=30.0), GcodeSettings())
    moved = PlotterSettings(position_mm=(290.0, 10.0))
    with pytest.raises(UsageError, match=r"does not fit .*move it \(plotter\.position_mm\)"):
        export_word(word, ExportSettings(formats=("svg",), plotter=moved))
    with pytest.raises(UsageError, match=r"needs a feed of \d+ mm/min, more than gcode\.max_feed"):
        export_word(
            word, ExportSettings(formats=("gcode",), gcode=GcodeSettings(max_feed_mm_min=500))
        )
    undated = replace(word, dmp=None)
    with pytest.raises(UsageError, match=r"has no DMP: gcode follow"):
        export_word(undated, ExportSettings(formats=("svg", "gcode")))
    assert export_word(undated, ExportSettings(formats=("svg", "hpgl"))).metadata["plotter"]
    with pytest.raises(UsageError, match=r"unknown format 'pdf'"):
        ExportSettings(formats=("svg", "pdf"))


# ----------------------------------------------------------------------------- HPGL and SVG


def test_hpgl_reads_back_to_the_ink_within_the_plotters_resolution(word, tmp_path):
    result = export_word(word, ExportSettings(formats=("hpgl",)), tmp_path)
    strokes, unit = parse_hpgl(result.files["hpgl"].read_text())
    place = _centred(word)
    ink = [place(p) for p in _ink_pieces(word)]
    resolution = unit * math.sqrt(2) / 2 + 1e-9  # half a plotter unit, both axes
    assert _nearest(np.concatenate(strokes), np.concatenate(ink)).max() <= resolution
    assert _nearest(np.concatenate(ink), np.concatenate(strokes)).max() <= resolution
    n_points = sum(len(s) for s in strokes)
    assert _length(strokes) == pytest.approx(_length(ink), abs=n_points * unit)  # no travel inked


def test_hpgl_refuses_a_word_on_the_sheet_but_out_of_the_plotters_reach(word):
    # the hp7475a's a4 area starts 10 mm from the sheet's left edge (vpype's profile)
    near_edge = PlotterSettings(position_mm=(3.0, 100.0))
    export_word(word, ExportSettings(formats=("svg",), plotter=near_edge))  # on the sheet
    with pytest.raises(UsageError, match=r"does not fit the area the hp7475a reaches on a4"):
        export_word(word, ExportSettings(formats=("hpgl",), plotter=near_edge))
    with pytest.raises(UsageError, match=r"has no paper of 300 x 200 mm"):
        export_word(word, ExportSettings(formats=("hpgl",), plotter=PlotterSettings((300, 200))))
    a3 = PlotterSettings(paper_mm=(420.0, 297.0))
    text = export_word(word, ExportSettings(formats=("hpgl",), plotter=a3)).metadata
    assert text["plotter"]["hpgl_device"] == "hp7475a"
    with pytest.raises(UsageError, match=r"not a plotter vpype knows"):
        export_word(word, ExportSettings(formats=("hpgl",), hpgl=HpglSettings(device="nope")))


def test_plotter_svg_is_true_size_pen_down_only_and_reads_back_with_vpype(word, tmp_path):
    import xml.etree.ElementTree as ET

    import vpype as vp

    path = export_word(word, ExportSettings(formats=("svg",)), tmp_path).files["svg"]
    root = ET.parse(path).getroot()
    assert (root.get("width"), root.get("height")) == ("29.7cm", "21.0cm")
    tags = {el.tag.split("}")[-1] for el in root.iter()}
    assert "rect" not in tags and "polyline" in tags  # no background
    lines, width, height = vp.read_svg(str(path), quantization=0.01)
    mm = vp.convert_length("mm")
    assert_allclose([width / mm, height / mm], A4, atol=0.01)
    read = [np.column_stack([line.real / mm, A4[1] - line.imag / mm]) for line in lines]
    place = _centred(word)
    ink = [place(p) for p in _ink_pieces(word)]
    assert _nearest(np.concatenate(read), np.concatenate(ink)).max() < 1e-3
    assert _nearest(np.concatenate(ink), np.concatenate(read)).max() < 1e-3
    assert _length(read) == pytest.approx(_length(ink), rel=1e-5)  # no pen-up travel drawn
