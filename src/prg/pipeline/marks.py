"""Delayed strokes: the dots of ``i`` and ``j`` and the bars of ``t`` and ``f``.

People write a word in one cursive movement, then go back to dot the i's and cross the t's. The
models decode single strokes (the paper keeps only single-stroke samples; the synthetic source
drops the dots), so after the cursive body the word gets its **marks**, each a separate pen-down
stroke reached by a pen-up travel, left to right. They are placed by explicit rules from each
letter's own laid-out geometry (centimetres, baseline ``y = 0``, :mod:`prg.pipeline.layout`) and
sized with the letter:

* **dot** (letters in ``MarkSettings.dotted``): a small circle of radius ``dot_radius * H``
  centred above the stem's top: at the x of the letter's highest point (where the stem of an
  ``i`` or ``j`` ends), ``dot_gap * H`` above that point plus the radius;
* **bar** (letters in ``MarkSettings.crossed``): a straight stroke ``bar_width * H`` long, left
  to right, at the x-height line (``bar_height`` times the x-height; kept inside the letter's
  own height band, see :func:`bar_height_cm`), centred on the stem: the crossing of the letter's
  path with that line nearest the letter's highest point.

``H`` is ``LayoutSettings.letter_height`` times the letter's own scale (1 unless the layout's width
guard made the letter shorter than its band; at least :data:`MIN_SCALE`), so a mark keeps its
proportion to its letter.

The paper's single stroke is ``GenerateSettings.delayed_strokes=False``. How the marks are timed
(straight, minimum-jerk rest-to-rest strokes, not DMPs) is in :mod:`prg.pipeline.timing`.
"""

from __future__ import annotations

import numpy as np

from prg.pipeline.layout import LayoutSettings, letter_band
from prg.pipeline.settings import MarkSettings

DOT_POINTS = 13  # a closed circle: 12 chords (under 0.01 mm from the true circle)
BAR_STEP_CM = 0.05  # the bar's points are this far apart (as the connection strokes' delta)


MIN_SCALE = 0.25  # marks of a letter the width guard flattened keep a quarter of their size


def _scale(points: np.ndarray, char: str, layout: LayoutSettings) -> float:
    """The letter's height over its band's: 1 unless the width guard shrank it, and at least
    :data:`MIN_SCALE`."""
    bottom, top = letter_band(char, layout)
    height = float(np.ptp(points[:, 1]))
    return float(np.clip(height / (top - bottom), MIN_SCALE, 1.0)) if top > bottom else 1.0


def dot_for(points: np.ndarray, char: str, settings: MarkSettings, layout: LayoutSettings):
    """The dot above a laid-out letter: a closed circle, shape (DOT_POINTS, 2), starting at its
    top and going counter-clockwise."""
    h = layout.letter_height * _scale(points, char, layout)
    top = points[int(np.argmax(points[:, 1]))]
    radius = settings.dot_radius * h
    centre = top + np.array([0.0, settings.dot_gap * h + radius])
    angle = np.pi / 2 + np.linspace(0.0, 2 * np.pi, DOT_POINTS)
    return centre + radius * np.column_stack([np.cos(angle), np.sin(angle)])


def bar_height_cm(points: np.ndarray, layout: LayoutSettings, settings: MarkSettings) -> float:
    """The bar's height: ``bar_height`` times the x-height, kept between 20 % and 85 % of the
    letter's own height so that the bar crosses the stem even on a letter the layout shrank."""
    low, high = float(points[:, 1].min()), float(points[:, 1].max())
    wanted = settings.bar_height * layout.x_height * layout.letter_height
    return float(np.clip(wanted, low + 0.2 * (high - low), low + 0.85 * (high - low)))


def stem_crossings(points: np.ndarray, y: float) -> np.ndarray:
    """x of every crossing of the path ``points`` (n, 2) with the line at height ``y``."""
    y0, y1 = points[:-1, 1], points[1:, 1]
    span = (np.minimum(y0, y1) <= y) & (np.maximum(y0, y1) >= y) & (y0 != y1)
    u = (y - y0[span]) / (y1[span] - y0[span])
    return points[:-1, 0][span] + u * (points[1:, 0][span] - points[:-1, 0][span])


def bar_for(points: np.ndarray, char: str, settings: MarkSettings, layout: LayoutSettings):
    """The bar across a laid-out letter's stem, left to right, shape (n, 2)."""
    h = layout.letter_height * _scale(points, char, layout)
    y = bar_height_cm(points, layout, settings)
    top_x = points[int(np.argmax(points[:, 1])), 0]
    crossings = stem_crossings(points, y)
    # a path from its lowest to its highest point crosses every height between: never empty
    x = crossings[int(np.argmin(np.abs(crossings - top_x)))] if len(crossings) else top_x
    half = settings.bar_width * h / 2
    n = max(2, int(np.ceil(2 * half / BAR_STEP_CM)) + 1)
    return np.column_stack([np.linspace(x - half, x + half, n), np.full(n, y)])


#: A crossed letter is cut where its foot has risen this share of the letter's height.
EXIT_RISE = 0.25


def crossed_exit(points: np.ndarray) -> np.ndarray:
    """A crossed letter (t, f) cut where a writer leaves it: its foot, the bar drawn later.

    Some writers' one-stroke ``t`` goes down the stem, round the foot and back up and across to
    draw its bar; laid out beside other letters that return reads as a ``b`` ("little" read as
    "libble"), and the next connection leaves from inside the letter. With the bar written as a
    delayed stroke, the letter ends where its foot has risen ``EXIT_RISE`` of the letter's
    height, when the rest of the path goes back left of that point (a return to the stem); a
    letter whose foot simply leaves to the right, or that ends at its foot, is kept whole.

    Parameters
    ----------
    points : ndarray, shape (n, 2)
        The letter, y up.

    Returns
    -------
    ndarray, shape (m, 2), m <= n
        The letter up to its exit (a prefix of ``points``).
    """
    y = points[:, 1]
    height = float(np.ptp(y))
    top = int(np.argmax(y))
    foot = top + int(np.argmin(y[top:]))
    risen = np.nonzero(y[foot:] - y[foot] > EXIT_RISE * height)[0]
    if height <= 0 or not len(risen):
        return points
    cut = foot + int(risen[0])
    returns = points[cut:, 0].min() < points[cut, 0] - EXIT_RISE * height
    return points[: cut + 1] if returns and cut >= 2 else points


def letter_marks(
    letters: list[np.ndarray],
    text: str,
    settings: MarkSettings | None = None,
    layout: LayoutSettings | None = None,
) -> list[tuple[int, str, np.ndarray]]:
    """The delayed strokes of laid-out letters, in writing order (left to right).

    Parameters
    ----------
    letters : list of ndarray, each shape (n_i, 2)
        The letters in centimetres (:func:`prg.pipeline.layout.layout_letters`), one per
        non-space character of ``text``.
    text : str
    settings, layout : optional

    Returns
    -------
    list of (letter index, ``"dot"`` or ``"bar"``, points (m, 2))
    """
    settings = settings or MarkSettings()
    layout = layout or LayoutSettings()
    chars = [c for c in text if c != " "]
    out = []
    for i, (char, points) in enumerate(zip(chars, letters)):
        kind = settings.mark_of(char)
        if kind == "dot":
            out.append((i, kind, dot_for(points, char, settings, layout)))
        elif kind == "bar":
            out.append((i, kind, bar_for(points, char, settings, layout)))
    return out


__all__ = [
    "MarkSettings",
    "bar_for",
    "bar_height_cm",
    "crossed_exit",
    "dot_for",
    "letter_marks",
    "stem_crossings",
]
