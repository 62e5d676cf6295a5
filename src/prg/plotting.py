"""Figures and colours: matplotlib's pyplot on the headless Agg backend, and the one palette.

Palette
-------
Every colour the project draws with, named by what it shows, as 8-bit RGB (Rerun takes the tuples
as they are; :func:`hex_colour` writes them for matplotlib and SVG). The Rerun recordings
(:mod:`prg.recording`) read them from here.

=================  ===============  ==========================================================
name               RGB              what
=================  ===============  ==========================================================
``PAPER``          255, 255, 255    the page: background of 2D views, ink pictures and figures
``SHEET``          250, 250, 250    the simulated sheet of paper in the 3D scene
``TABLE``          200, 170, 130    the simulated table top
``SCENE``          235, 235, 240    background of the 3D scene view
``INK``            20, 20, 20       written letters and the simulated ink (recordings, ink PNGs)
``FIGURE_INK``     0, 0, 0          letters in saved figures of a word (PNG, SVG)
``CONNECTION``     214, 39, 40      connection strokes in figures (one colour for all of them)
``MARK``           148, 103, 189    delayed strokes (i/j dots, t/f bars) in highlighted figures
``PEN_UP``         150, 150, 150    pen-up travel between words
``TARGET``         190, 190, 190    the path the DMP was fitted to
``COMMANDED``      120, 170, 255    the pen-down strokes the simulated robot was commanded
``PEN``            31, 119, 180     the pen's point and the path it has written so far
``PEN_BODY``       25, 50, 180      the simulated pen's body
``PEN_TRACE``      255, 150, 40     the simulated pen tip's path in 3D (on and off the paper)
``WAVEFORM``       44, 160, 44      the spoken command's waveform
=================  ===============  ==========================================================

In a recording each connection stroke has its own colour (:func:`distinct_colours`).
"""

from __future__ import annotations

import colorsys

import numpy as np

RGB = tuple[int, int, int]

PAPER: RGB = (255, 255, 255)
SHEET: RGB = (250, 250, 250)
TABLE: RGB = (200, 170, 130)
SCENE: RGB = (235, 235, 240)
INK: RGB = (20, 20, 20)
FIGURE_INK: RGB = (0, 0, 0)
CONNECTION: RGB = (214, 39, 40)  # matplotlib's tab:red
MARK: RGB = (148, 103, 189)  # matplotlib's tab:purple
PEN_UP: RGB = (150, 150, 150)
SPACE: RGB = (158, 158, 158)  # the dashed pen-up move over a space in word figures
TARGET: RGB = (190, 190, 190)
COMMANDED: RGB = (120, 170, 255)
PEN: RGB = (31, 119, 180)  # matplotlib's tab:blue
PEN_BODY: RGB = (25, 50, 180)
PEN_TRACE: RGB = (255, 150, 40)
WAVEFORM: RGB = (44, 160, 44)  # matplotlib's tab:green


def hex_colour(rgb: RGB) -> str:
    """``"#rrggbb"`` of an 8-bit RGB colour, for matplotlib and SVG: ``(214, 39, 40)`` ->
    ``"#d62728"``."""
    return "#{:02x}{:02x}{:02x}".format(*rgb)


def distinct_colours(n: int) -> np.ndarray:
    """``n`` clearly different colours (hues a golden angle apart), uint8 RGB, shape (n, 3)."""
    hues = (0.02 + np.arange(n) * 0.618033988749895) % 1.0
    rgb = [colorsys.hsv_to_rgb(h, 0.85, 0.85) for h in hues]
    return np.round(np.array(rgb, dtype=np.float64).reshape(n, 3) * 255).astype(np.uint8)


def pyplot():
    """matplotlib's pyplot on the non-interactive Agg backend (headless, no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt
