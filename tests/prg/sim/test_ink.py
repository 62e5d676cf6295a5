"""Tests of ``prg.sim.ink`` (moved from the suite on: the simulated robot writes: accuracy, ink,
lifts between words, workspace, IK, both arms, outputs, and the Rerun recording read back from
disk)."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from prg.sim import (
    ink_png,
    ink_svg,
)
from prg.sim.geometry import bounding_box
from tests.helpers.sim import panda_hi  # noqa: F401 (fixtures)


def test_ink_png_and_svg_are_true_to_scale(tmp_path, panda_hi):
    strokes = panda_hi.ink_strokes()
    svg = ink_svg(strokes, tmp_path / "ink.svg").read_text()
    root = ET.fromstring(svg)
    polylines = root.findall("{http://www.w3.org/2000/svg}polyline")
    assert len(polylines) == len(strokes)
    low, high = bounding_box(np.concatenate(strokes))
    assert float(root.get("width").removesuffix("cm")) == pytest.approx(
        high[0] - low[0] + 0.6, abs=1e-3
    )
    from PIL import Image

    with Image.open(ink_png(strokes, tmp_path / "ink.png", dpi=300)) as image:
        assert image.size[0] == pytest.approx((high[0] - low[0] + 0.6) / 2.54 * 300, abs=2)
        assert (np.asarray(image.convert("L")) < 100).any()
