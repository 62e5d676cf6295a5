"""A written word for pen plotters: G-code (GRBL), HPGL and plotter SVG, at true size.

The **paper frame** here is the plotter's: millimetres from the sheet's lower-left corner, x
along the writing line, y up the page (the word's own axes, scaled by 10 mm/cm times ``scale``).
:func:`place_word` puts the word's ink (its pen-down pieces, ``polylines(highlight=False)``) on
the sheet: centred, or with its bounding box's lower-left corner at ``position_mm``.

* **SVG** (:func:`svg_text`): the ink as polylines, page size and ``viewBox`` of the sheet (cm
  and CSS pixels: true size), no background, no pen-up travel — written by vpype.
* **HPGL** (:func:`hpgl_text`): the ink for a plotter of vpype's device profiles (``hp7475a``
  ...), paper chosen by size; vpype converts to plotter units with the device's origin and axes.
* **G-code** (:func:`gcode_text`, GRBL): the word's **timed** motion, its DMP rollout
  (:func:`prg.sim.word_samples`): every pen-down step between consecutive samples is one
  ``G1`` with the feed rate ``F = distance / dt`` (mm/min), so the plotter writes at the DMP's
  speed and its pen-down time is the plan's. Units mm (``G21``), absolute (``G90``); the pen
  moves by Z (``G1 Z<down>``/``G0 Z<up>``) or by two servo commands; ``origin_mm`` shifts the
  paper on the machine. A word that does not fit the paper, or a feed above
  ``max_feed_mm_min``, is refused with one line.
"""

from __future__ import annotations

import io
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prg.errors import UsageError
from prg.export.settings import (
    UNITS,
    GcodeSettings,
    HpglSettings,
    PlotterSettings,
)

if TYPE_CHECKING:
    from prg.pipeline.word import WordTrajectory

__all__ = [
    "GcodeProgram",
    "GcodeSettings",
    "HpglSettings",
    "Placement",
    "PlotterSettings",
    "TimedStroke",
    "gcode_text",
    "hpgl_text",
    "ink_strokes",
    "place_word",
    "svg_text",
    "timed_strokes",
]

_Float = NDArray[np.float64]

# ----------------------------------------------------------------------------- placement


@dataclass(frozen=True)
class Placement:
    """Word centimetres to sheet millimetres: ``offset_mm + mm_per_cm * points``."""

    mm_per_cm: float
    offset_mm: _Float

    def __call__(self, points_cm: ArrayLike) -> _Float:
        return self.offset_mm + self.mm_per_cm * np.asarray(points_cm, dtype=np.float64)


def ink_strokes(word: WordTrajectory) -> list[_Float]:
    """The word's ink as pen-down strokes (cm): its pen-down pieces
    (``polylines(highlight=False)``), a piece that starts where the previous one ended joined to
    it (a letter and the connection after it are one stroke; the pen is lifted only between
    words and for delayed strokes)."""
    strokes: list[_Float] = []
    for _, piece in word.polylines(highlight=False):
        piece = np.asarray(piece, dtype=np.float64)
        if strokes and np.array_equal(strokes[-1][-1], piece[0]):
            strokes[-1] = np.concatenate([strokes[-1], piece[1:]])
        else:
            strokes.append(piece)
    return strokes


def place_word(word: WordTrajectory, settings: PlotterSettings) -> Placement:
    """Where the word's ink goes on the sheet (mm), from ``settings``' scale and position."""
    ink = np.concatenate(ink_strokes(word))
    low, high = ink.min(axis=0), ink.max(axis=0)
    mm_per_cm = 10.0 * settings.scale
    size = (high - low) * mm_per_cm
    if settings.position_mm is None:
        corner = (np.asarray(settings.paper_mm) - size) / 2
    else:
        corner = np.asarray(settings.position_mm, dtype=np.float64)
    return Placement(mm_per_cm, corner - mm_per_cm * low)


def check_fits(
    strokes_mm: Sequence[_Float], area_mm: tuple[_Float, _Float], what: str, text: str
) -> None:
    """Refuse strokes (mm) that leave the rectangle ``area_mm`` = (lower-left, upper-right)."""
    pts = np.concatenate(strokes_mm)
    low, high = pts.min(axis=0), pts.max(axis=0)
    lo, hi = (np.asarray(a, dtype=np.float64) for a in area_mm)
    if np.all(low >= lo - 1e-9) and np.all(high <= hi + 1e-9):
        return
    w, h = high - low
    raise UsageError(
        f"word {text[:40]!r} ({w:.1f} x {h:.1f} mm, from ({low[0]:.1f}, {low[1]:.1f}) to "
        f"({high[0]:.1f}, {high[1]:.1f}) mm) does not fit {what} (from ({lo[0]:.1f}, "
        f"{lo[1]:.1f}) to ({hi[0]:.1f}, {hi[1]:.1f}) mm): make it smaller (scale) or move it "
        "(plotter.position_mm)"
    )


def _sheet(settings: PlotterSettings) -> tuple[_Float, _Float]:
    return np.zeros(2), np.asarray(settings.paper_mm, dtype=np.float64)


def _sheet_name(settings: PlotterSettings) -> str:
    w, h = settings.paper_mm
    return f"the {w:g} x {h:g} mm paper (plotter.paper_mm)"


# ----------------------------------------------------------------------------- timed motion


@dataclass(frozen=True)
class TimedStroke:
    """One pen-down run of the word's timed motion: sheet positions (mm) and times (s)."""

    points_mm: _Float
    t: _Float

    @property
    def duration_s(self) -> float:
        return float(self.t[-1] - self.t[0])


def timed_strokes(
    word: WordTrajectory, placement: Placement, dt: float, tempo: float = 1.0
) -> list[TimedStroke]:
    """The word's timed pen-down motion on the sheet: :func:`prg.sim.word_samples` (the DMP
    rollout, every ``dt`` s, duration times ``tempo``), split into its pen-down runs.

    Raises
    ------
    UsageError
        If the word has no DMP: its timing is the DMP's.
    """
    from prg.sim.geometry import runs
    from prg.sim.writing import word_samples

    if word.dmp is None:
        raise UsageError(
            f"word {word.text[:40]!r} has no DMP: timed formats (G-code, MCAP, CSV) follow the "
            "DMP's timing; write the word with prg-write (svg and hpgl need no timing)"
        )
    samples, t, down = word_samples(word, dt, tempo)
    placed = placement(samples)
    return [TimedStroke(placed[a:b], t[a:b]) for a, b in runs(down)]


# ----------------------------------------------------------------------------- G-code


@dataclass(frozen=True)
class GcodeProgram:
    """A G-code program and what it does.

    Attributes
    ----------
    text : str
    pen_down_s : float
        Time with the pen down: the ``G1`` moves (distance / feed) and the ``G4`` rests between
        them (where the plan's pen stands still), not the pen's own up and down moves.
    moves : int
        ``G1`` writing moves.
    strokes : int
    max_feed_mm_min : float
    """

    text: str
    pen_down_s: float
    moves: int
    strokes: int
    max_feed_mm_min: float


def _fmt(value: float, decimals: int) -> str:
    text = f"{value:.{decimals}f}"
    return "0" + text[text.index(".") :] if text.startswith("-0.") and float(text) == 0 else text


def gcode_text(
    strokes: Sequence[TimedStroke],
    plotter: PlotterSettings,
    settings: GcodeSettings,
    title: str = "",
) -> GcodeProgram:
    """The GRBL program writing ``strokes`` (sheet mm) at their timing.

    Every step between consecutive samples of a stroke is one ``G1 X Y F`` with
    ``F = 60 * distance / dt`` (``units`` per minute), the distance measured between the coordinates as
    written (rounded to ``settings.decimals``), so a plotter that keeps its feed rates spends
    exactly the samples' time. Steps that round to no motion (the pen at rest, at a stroke's
    start and end) become ``G4 P<s>`` dwells with the pen down, so no time is lost either.

    Raises
    ------
    UsageError
        A stroke off the sheet, or a feed above ``settings.max_feed_mm_min``.
    """
    # Written here rather than by vpype-gcode: its profiles expand fixed templates per segment
    # (the coordinates, their differences and indices), with no per-segment value such as a feed
    # rate from the timing, which is the point of this program.
    if not strokes:
        raise UsageError("nothing to write: the word has no pen-down motion")
    check_fits([s.points_mm for s in strokes], _sheet(plotter), _sheet_name(plotter), title)
    s = settings
    nd = s.decimals
    code, unit_name, per_mm = UNITS[s.units]
    origin = np.asarray(s.origin_mm, dtype=np.float64)
    if s.pen == "z":
        pen_up = [f"G0 Z{_fmt(s.z_up_mm * per_mm, nd)}"]
        pen_down = [f"G1 Z{_fmt(s.z_down_mm * per_mm, nd)} F{s.z_feed_mm_min * per_mm:.4f}"]
    else:
        wait = [f"G4 P{s.servo_wait_s:.3f}"] if s.servo_wait_s > 0 else []
        pen_up, pen_down = [s.servo_up, *wait], [s.servo_down, *wait]
    safe_title = re.sub(r"[^A-Za-z0-9 ._-]", "?", title)[:60]
    lines = [
        f"; prg-export: {safe_title}" if safe_title else "; prg-export",
        f"{code} ; {unit_name}",
        "G90 ; absolute coordinates",
        "G94 ; feed per minute",
        *pen_up,
    ]
    pen_down_s, moves, fastest = 0.0, 0, 0.0
    for stroke in strokes:
        pts = np.round((stroke.points_mm + origin) * per_mm * 10**nd) / 10**nd
        x, y = (_fmt(v, nd) for v in pts[0])
        lines += [f"G0 X{x} Y{y}", *pen_down]
        rest = 0.0
        for i in range(1, len(pts)):
            dt = float(stroke.t[i] - stroke.t[i - 1])
            distance = math.hypot(*(pts[i] - pts[i - 1]))
            if distance == 0.0:  # the pen rests: kept as a dwell before the next move
                rest += dt
                continue
            if rest > 0:
                lines.append(f"G4 P{rest:.4f}")
                pen_down_s += float(f"{rest:.4f}")
                rest = 0.0
            feed = 60.0 * distance / dt  # units per minute
            written = f"{feed:.4f}"
            fastest = max(fastest, feed / per_mm)
            x, y = (_fmt(v, nd) for v in pts[i])
            lines.append(f"G1 X{x} Y{y} F{written}")
            pen_down_s += 60.0 * distance / float(written)
            moves += 1
        if rest > 0:
            lines.append(f"G4 P{rest:.4f}")
            pen_down_s += float(f"{rest:.4f}")
        lines += pen_up
    if s.max_feed_mm_min is not None and fastest > s.max_feed_mm_min:
        raise UsageError(
            f"word {title[:40]!r} needs a feed of {fastest:.0f} mm/min, more than "
            f"gcode.max_feed_mm_min={s.max_feed_mm_min:g}: write slower (tempo >= "
            f"{math.ceil(fastest / s.max_feed_mm_min * 100) / 100:g} times the current one)"
        )
    lines.append("M2 ; end")
    return GcodeProgram("\n".join(lines) + "\n", pen_down_s, moves, len(strokes), fastest)


# ----------------------------------------------------------------------------- vpype: SVG, HPGL


def _document(strokes_mm: Sequence[_Float], paper_mm: tuple[float, float]) -> Any:
    """A vpype Document of the strokes: CSS pixels, y down from the sheet's top-left corner."""
    import vpype as vp

    px = vp.convert_length("mm")
    width, height = paper_mm
    lines = vp.LineCollection()
    for stroke in strokes_mm:
        lines.append((stroke[:, 0] + 1j * (height - stroke[:, 1])) * px)
    doc = vp.Document(page_size=(width * px, height * px))
    doc.add(lines, 1)
    return doc


def svg_text(strokes_mm: Sequence[_Float], plotter: PlotterSettings, title: str = "") -> str:
    """A plotter SVG of the strokes (sheet mm): the sheet's size in cm, its ``viewBox`` in CSS
    pixels (96 per inch), one black polyline per stroke, no background, no pen-up travel;
    vpype's ``write_svg`` (no date: the same word gives the same file)."""
    import vpype as vp

    check_fits(strokes_mm, _sheet(plotter), _sheet_name(plotter), title)
    out = io.StringIO()
    vp.write_svg(
        out,
        _document(strokes_mm, plotter.paper_mm),
        source_string=f"prg-export: {title}",
        set_date=False,
        color_mode="none",
    )
    return out.getvalue()


def _paper_config(plotter: PlotterSettings, settings: HpglSettings) -> tuple[Any, Any]:
    """vpype's plotter and paper configuration for the settings; the paper must be the sheet."""
    import vpype as vp

    device = vp.config_manager.get_plotter_config(settings.device)
    if device is None:
        raise UsageError(
            f"hpgl.device {settings.device!r} is not a plotter vpype knows: choose "
            + ", ".join(vp.config_manager.get_plotter_list())
        )
    mm = vp.convert_length("mm")
    sizes = {
        p.name: tuple(round(v / mm, 1) for v in p.paper_size)
        for p in device.paper_configs
        if p.paper_size is not None
    }
    known = ", ".join(f"{n} ({w:g} x {h:g} mm)" for n, (w, h) in sizes.items())
    if settings.page is not None:
        paper = device.paper_config(settings.page)
        if paper is None:
            raise UsageError(
                f"hpgl.page {settings.page!r}: the {device.name} takes "
                + ", ".join(p.name for p in device.paper_configs)
            )
    else:
        match = [
            device.paper_config(n)
            for n, size in sizes.items()
            if np.allclose(size, plotter.paper_mm, atol=0.5)
        ]
        if not match:
            raise UsageError(
                f"the {device.name} has no paper of {plotter.paper_mm[0]:g} x "
                f"{plotter.paper_mm[1]:g} mm (plotter.paper_mm): it takes {known}; set "
                "plotter.paper_mm to one of them (or hpgl.page)"
            )
        paper = match[0]
    if paper.paper_size is not None:
        size = np.asarray(paper.paper_size) / mm
        if not np.allclose(size, plotter.paper_mm, atol=0.5):
            raise UsageError(
                f"hpgl.page {paper.name!r} of the {device.name} is {size[0]:.1f} x "
                f"{size[1]:.1f} mm (as the plotter holds it) but plotter.paper_mm is "
                f"{plotter.paper_mm[0]:g} x {plotter.paper_mm[1]:g}: make them the same"
            )
    elif paper.paper_orientation is not None and (
        (paper.paper_orientation == "landscape") != (plotter.paper_mm[0] > plotter.paper_mm[1])
    ):
        raise UsageError(
            f"hpgl.page {paper.name!r} of the {device.name} takes {paper.paper_orientation} "
            "paper: swap plotter.paper_mm"
        )
    return device, paper


def _plottable(device: Any, paper: Any, paper_mm: tuple[float, float]) -> tuple[_Float, _Float]:
    """The area the plotter reaches, as (lower-left, upper-right) in sheet mm (y up).

    vpype crops whatever lies outside the device's ``x_range``/``y_range`` without a word; this
    inverts its mapping from the page to plotter units (translate by the origin, scale by the
    unit, y flipped when the plotter's y axis points up; the paper turned by 180 degrees for
    ``rotate_180``) to refuse such a word instead."""
    import vpype as vp

    mm = vp.convert_length("mm")
    width, height = paper_mm
    if paper.x_range is None or paper.y_range is None:
        return np.array([-np.inf, -np.inf]), np.array([np.inf, np.inf])
    unit = device.plotter_unit_length / mm
    ox, oy = (v / mm for v in paper.origin_location)
    if paper.origin_location_reference == "botleft":
        oy = height - oy
    xs = ox + np.asarray(paper.x_range, dtype=np.float64) * unit
    ys = oy + np.asarray(paper.y_range, dtype=np.float64) * unit * (-1 if paper.y_axis_up else 1)
    if paper.rotate_180:
        xs, ys = width - xs, height - ys
    down = np.sort(ys)  # page y (down from the top)
    return np.array([xs.min(), height - down[1]]), np.array([xs.max(), height - down[0]])


def hpgl_text(
    strokes_mm: Sequence[_Float],
    plotter: PlotterSettings,
    settings: HpglSettings,
    title: str = "",
) -> str:
    """HPGL of the strokes (sheet mm) for ``settings.device`` on the paper of the sheet's size,
    written by vpype's ``write_hpgl`` (no centring, no scaling); a word outside the area the
    plotter reaches is refused (vpype would crop it silently)."""
    import vpype as vp

    device, paper = _paper_config(plotter, settings)
    check_fits(strokes_mm, _sheet(plotter), _sheet_name(plotter), title)
    check_fits(
        strokes_mm,
        _plottable(device, paper, plotter.paper_mm),
        f"the area the {device.name} reaches on {paper.name} paper",
        title,
    )
    out = io.StringIO()
    vp.write_hpgl(
        out,
        _document(strokes_mm, plotter.paper_mm),
        page_size=paper.name,
        landscape=plotter.paper_mm[0] > plotter.paper_mm[1],
        center=False,
        device=device.name,
        velocity=settings.velocity,
        absolute=settings.absolute,
        quiet=True,
    )
    return out.getvalue()
