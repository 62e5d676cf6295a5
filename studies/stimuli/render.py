"""Drawing every sample alike: one :class:`RenderStyle`, one renderer, opaque PNG names."""

from __future__ import annotations

import hashlib
import math
from collections.abc import Sequence
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from prg.errors import UsageError
from studies.stimuli.sample import Sample

MAX_RENDER_PX = 4000  #: a stimulus PNG's width or height
MAX_RENDER_PIXELS = 64_000_000  #: supersampled pixels drawn per stimulus (64 MB in grey)


@dataclass(frozen=True)
class RenderStyle:
    """How every stimulus is drawn.

    Attributes
    ----------
    width_px, height_px : int
        PNG size.
    margin_px : int
        Blank border on every side (ink never enters it).
    stroke_px : float
        Ink width.
    supersample : int
        Drawn this many times larger, then reduced (anti-aliasing).
    """

    width_px: int = 720
    height_px: int = 180
    margin_px: int = 14
    stroke_px: float = 4.0
    supersample: int = 4

    def __post_init__(self) -> None:
        for name, high in (
            ("width_px", MAX_RENDER_PX),
            ("height_px", MAX_RENDER_PX),
            ("supersample", 8),
        ):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= high:
                raise UsageError(
                    f"render.{name} must be an integer from 1 to {high}, got {value!r}"
                )
        if (
            isinstance(self.margin_px, bool)
            or not isinstance(self.margin_px, int)
            or self.margin_px < 0
        ):
            raise UsageError(f"render.margin_px must be an integer >= 0, got {self.margin_px!r}")
        if (
            isinstance(self.stroke_px, bool)
            or not isinstance(self.stroke_px, int | float)
            or not 0 < self.stroke_px < math.inf
        ):
            raise UsageError(
                f"render.stroke_px must be a positive finite number, got {self.stroke_px!r}"
            )
        drawn = self.width_px * self.height_px * self.supersample**2
        if drawn > MAX_RENDER_PIXELS:
            raise UsageError(
                f"render: width_px x height_px x supersample² is {drawn} pixels per stimulus; "
                f"at most {MAX_RENDER_PIXELS}"
            )
        inner = min(self.width_px, self.height_px) - 2 * self.margin_px - self.stroke_px
        if inner <= 0:
            raise UsageError("render: margins and stroke leave no room for the word")

    @classmethod
    def from_dict(cls, settings: dict) -> RenderStyle:
        """From the study's ``render`` section; names an unknown key."""
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(settings) - known)
        if unknown:
            raise UsageError(f"render: unknown key {unknown[0]!r}: accepted are {sorted(known)}")
        return cls(**settings)


def fit_transform(
    strokes: Sequence[np.ndarray], style: RenderStyle
) -> tuple[float, np.ndarray, np.ndarray]:
    """Scale and offsets that map y-up points to centred pixel coordinates (y down).

    The ink's bounding box is scaled to fill the room inside the margins (less half a stroke
    on each side) in height, or in width where the word is too wide, and centred.

    Returns
    -------
    scale : float
    center_in : ndarray, shape (2,)
        Centre of the ink's bounding box (input units).
    center_out : ndarray, shape (2,)
        Centre of the image (pixels).
    """
    pts = np.concatenate([np.asarray(s, dtype=np.float64).reshape(-1, 2) for s in strokes])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    size = hi - lo
    room = np.array(
        [
            style.width_px - 2 * style.margin_px - style.stroke_px,
            style.height_px - 2 * style.margin_px - style.stroke_px,
        ]
    )
    ratios = [room[d] / size[d] for d in range(2) if size[d] > 1e-12 * max(1.0, abs(hi[d]))]
    scale = min(ratios) if ratios else 1.0
    return scale, (lo + hi) / 2, np.array([style.width_px / 2, style.height_px / 2])


def to_pixels(strokes: Sequence[np.ndarray], style: RenderStyle) -> list[np.ndarray]:
    """Strokes (y up) in the PNG's pixel coordinates (y down), as :func:`fit_transform` maps."""
    scale, c_in, c_out = fit_transform(strokes, style)
    flip = np.array([1.0, -1.0])
    return [c_out + (np.asarray(s, float).reshape(-1, 2) - c_in) * scale * flip for s in strokes]


def render_strokes(strokes: Sequence[np.ndarray], style: RenderStyle) -> Image.Image:
    """Draw strokes (y up, any unit) as a grayscale image: black ink on white.

    Returns
    -------
    PIL.Image.Image
        Mode ``"L"``, size ``(style.width_px, style.height_px)``.
    """
    strokes = [np.asarray(s, dtype=np.float64).reshape(-1, 2) for s in strokes]
    strokes = [s for s in strokes if len(s)]
    if not strokes:
        raise UsageError("nothing to draw: the sample has no points")
    k = style.supersample
    image = Image.new("L", (style.width_px * k, style.height_px * k), 255)
    draw = ImageDraw.Draw(image)
    width = max(1, round(style.stroke_px * k))
    radius = width / 2
    for pts in to_pixels(strokes, style):
        big = [(float(x) * k, float(y) * k) for x, y in pts]
        if len(big) > 1:
            draw.line(big, fill=0, width=width, joint="curve")
        for x, y in (big[0], big[-1]):  # round caps
            draw.ellipse((x - radius, y - radius, x + radius, y + radius), fill=0)
    return image.reduce(k)  # box filter: anti-aliased, no ringing into the margins


def render_sample(sample: Sample, style: RenderStyle) -> Image.Image:
    """:func:`render_strokes` of a sample's strokes."""
    try:
        return render_strokes(sample.strokes, style)
    except UsageError as err:
        raise UsageError(f"{sample.origin or sample.word}: {err}") from None


def stimulus_name(sample: Sample, salt: str) -> str:
    """An opaque, stable file name for a sample's PNG (reveals neither word nor writer)."""
    digest = hashlib.sha256(f"{salt}|{sample.word}|{sample.writer_id}".encode()).hexdigest()
    return f"{digest[:16]}.png"


def save_png(image: Image.Image, path: Path) -> Path:
    """Write a PNG without metadata (no creation time, no software tag)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    image.save(path, format="PNG", optimize=True)
    return path
