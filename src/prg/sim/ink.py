"""Pictures of the ink: the paper's texture, and the ink as PNG and SVG files.

Ink strokes are polylines in the paper frame (cm, y up, origin at the sheet's centre). Files
are written atomically (temporary name, then rename), like the word's renderings.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prg.files import atomic_path
from prg.plotting import INK, PAPER, hex_colour
from prg.sim.geometry import Paper

__all__ = ["draw_strokes", "ink_png", "ink_svg", "page_texture"]

PEN_WIDTH_MM = 0.5


def _atomic_write(path: Path, write) -> Path:
    """``write(tmp)`` to a temporary file beside ``path``, then rename it to ``path``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        write(tmp)
    return path


def draw_strokes(
    strokes: Sequence[ArrayLike],
    lower_left_cm: ArrayLike,
    size_px: tuple[int, int],
    px_per_cm: float,
    pen_width_mm: float = PEN_WIDTH_MM,
    background: tuple[int, int, int] = PAPER,
    ink: tuple[int, int, int] = INK,
) -> NDArray[np.uint8]:
    """Rasterise strokes (cm, y up) into an RGB image whose row 0 is the top.

    Parameters
    ----------
    strokes : sequence of array_like, each shape (n, 2)
    lower_left_cm : array_like, shape (2,)
        The paper-frame point at the image's lower-left corner.
    size_px : (width, height)
    px_per_cm : float
    pen_width_mm : float
        Line width; ends and joins are round.

    Returns
    -------
    ndarray of uint8, shape (height, width, 3)
    """
    from PIL import Image, ImageDraw

    width, height = size_px
    image = Image.new("RGB", (width, height), background)
    draw = ImageDraw.Draw(image)
    lo = np.asarray(lower_left_cm, dtype=np.float64)
    line = max(1, round(pen_width_mm / 10.0 * px_per_cm))
    r = line / 2
    for stroke in strokes:
        pts = np.asarray(stroke, dtype=np.float64).reshape(-1, 2)
        if not len(pts):
            continue
        px = np.column_stack(
            [(pts[:, 0] - lo[0]) * px_per_cm, height - (pts[:, 1] - lo[1]) * px_per_cm]
        )
        # thin out to one vertex per pixel: the same picture, far fewer segments
        keep = np.concatenate([[True], np.linalg.norm(np.diff(px, axis=0), axis=1) > 0])
        px = px[keep]
        if len(px) > 1:
            draw.line([tuple(p) for p in px], fill=ink, width=line, joint="curve")
        for x, y in (px[0], px[-1]):
            draw.ellipse([x - r, y - r, x + r, y + r], fill=ink)
    return np.asarray(image, dtype=np.uint8)


def page_texture(
    strokes: Sequence[ArrayLike], paper: Paper, px_per_cm: float = 60.0
) -> NDArray[np.uint8]:
    """The whole sheet with its ink, as the paper's texture (row 0 = the sheet's top edge)."""
    w, h = np.asarray(paper.size_cm, dtype=np.float64)
    size = (round(w * px_per_cm), round(h * px_per_cm))
    return draw_strokes(strokes, (-w / 2, -h / 2), size, px_per_cm)


def _frame(strokes: Sequence[ArrayLike], margin_cm: float) -> tuple[NDArray, NDArray]:
    pts = [np.asarray(s, dtype=np.float64).reshape(-1, 2) for s in strokes]
    pts = [p for p in pts if len(p)]
    if not pts:
        return np.zeros(2) - margin_cm, np.zeros(2) + margin_cm
    allp = np.concatenate(pts)
    return allp.min(axis=0) - margin_cm, allp.max(axis=0) + margin_cm


def ink_png(
    strokes: Sequence[ArrayLike],
    path: str | os.PathLike,
    dpi: int = 300,
    margin_cm: float = 0.3,
    pen_width_mm: float = PEN_WIDTH_MM,
) -> Path:
    """The ink, true to scale at ``dpi``, cropped to it with a margin; written atomically."""
    from PIL import Image

    lo, hi = _frame(strokes, margin_cm)
    px_per_cm = dpi / 2.54
    size = tuple(int(v) for v in np.ceil((hi - lo) * px_per_cm))
    image = draw_strokes(strokes, lo, size, px_per_cm, pen_width_mm)

    def save(tmp: Path) -> None:
        Image.fromarray(image).save(tmp, format="PNG", dpi=(dpi, dpi))

    return _atomic_write(Path(path), save)


def ink_svg(
    strokes: Sequence[ArrayLike],
    path: str | os.PathLike,
    title: str = "ink",
    margin_cm: float = 0.3,
    pen_width_mm: float = PEN_WIDTH_MM,
) -> Path:
    """The ink as SVG (1 user unit = 1 cm, one ``polyline`` per stroke); written atomically."""
    from xml.sax.saxutils import escape

    lo, hi = _frame(strokes, margin_cm)
    w, h = hi - lo
    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{w:.4f}cm" height="{h:.4f}cm" '
        f'viewBox="0 0 {w:.6f} {h:.6f}">',
        f"<title>{escape(title)}</title>",
        f'<rect width="100%" height="100%" fill="{hex_colour(PAPER)}"/>',
    ]
    for stroke in strokes:
        pts = np.asarray(stroke, dtype=np.float64).reshape(-1, 2)
        if not len(pts):
            continue
        if len(pts) == 1:
            pts = np.repeat(pts, 2, axis=0)
        coords = " ".join(f"{x - lo[0]:.4f},{hi[1] - y:.4f}" for x, y in pts)
        lines.append(
            f'<polyline class="ink" points="{coords}" fill="none" stroke="{hex_colour(INK)}" '
            f'stroke-width="{pen_width_mm / 10:.4f}" stroke-linecap="round" '
            'stroke-linejoin="round"/>'
        )
    lines.append("</svg>")
    text = "\n".join(lines) + "\n"
    return _atomic_write(Path(path), lambda tmp: tmp.write_text(text, encoding="utf-8"))
