"""The simulator's numeric core, as pure functions on arrays (no PyBullet here).

Frames and units
    The **paper frame** has its origin at the centre of the sheet, on its top surface; ``x`` runs
    along the writing line (to the writer's right), ``y`` up the page (away from the writer) and
    ``z`` out of the paper. Word and ink coordinates are centimetres in this frame (the word's own
    convention: y up); world coordinates are metres (PyBullet's). :class:`Paper` converts.

Contact band
    The pen is a tool offset without collision geometry: the pen tip *inks* the paper while its
    height above the surface is within ``[-band, +band]`` (:func:`in_contact`). Consecutive tip
    samples in contact form ink strokes.

Tracking error
    Distance, in the paper plane, between the commanded pen-down path and the ink, both ways
    (:func:`tracking_error`): every commanded sample to the nearest point of the ink polylines
    and every ink point to the nearest point of the commanded polylines. Mean and max are over
    both sets together (the max is the Hausdorff distance of the two paths).

Arc length, arc progress and the pen-down samples along a word are the generation pipeline's
(:mod:`prg.pipeline.motion`, which ``motion.csv`` is written with); they are re-exported here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prg.errors import UsageError
from prg.pipeline.motion import arc_length, arc_progress, pen_down_samples  # re-exported
from prg.sim.settings import Paper  # re-exported: the paper frame

__all__ = [
    "Paper",
    "arc_length",
    "arc_progress",
    "bounding_box",
    "distance_to_polylines",
    "in_contact",
    "max_ink_gap",
    "pen_down_samples",
    "place_points",
    "runs",
    "tracking_error",
]

_Float = NDArray[np.float64]


# ----------------------------------------------------------------------------- paths


def bounding_box(points: ArrayLike) -> tuple[_Float, _Float]:
    """Lower-left and upper-right corners of ``points`` (n, 2)."""
    pts = np.asarray(points, dtype=np.float64)
    return pts.min(axis=0), pts.max(axis=0)


def place_points(points: ArrayLike, anchor: ArrayLike, scale: float, target: ArrayLike) -> _Float:
    """Scale ``points`` about ``anchor`` and move ``anchor`` to ``target``.

    Parameters
    ----------
    points : array_like, shape (n, 2)
    anchor, target : array_like, shape (2,)
    scale : float

    Returns
    -------
    ndarray, shape (n, 2)
        ``target + scale * (points - anchor)``.
    """
    pts = np.asarray(points, dtype=np.float64)
    return np.asarray(target, dtype=np.float64) + scale * (pts - np.asarray(anchor, dtype=float))


def runs(mask: ArrayLike) -> list[tuple[int, int]]:
    """``(start, stop)`` index ranges (stop exclusive) of the consecutive True runs of ``mask``."""
    m = np.asarray(mask, dtype=bool).astype(np.int8)
    edges = np.diff(np.concatenate([[0], m, [0]]))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()))


# ----------------------------------------------------------------------------- ink and errors


def in_contact(heights_cm: ArrayLike, band_mm: float) -> NDArray[np.bool_]:
    """Whether the pen tip inks: its height above the paper is within ``+-band_mm``.

    Parameters
    ----------
    heights_cm : array_like, shape (n,)
        Tip height above the paper surface (cm; negative: pressed into it).
    band_mm : float
        Half-width of the contact band (mm), > 0.

    Returns
    -------
    ndarray of bool, shape (n,)
    """
    if not band_mm > 0:
        raise UsageError(f"contact band must be positive (mm), got {band_mm!r}")
    return np.abs(np.asarray(heights_cm, dtype=np.float64)) <= band_mm / 10.0


def distance_to_polylines(points: ArrayLike, polylines: Sequence[ArrayLike]) -> _Float:
    """Distance from each point to the nearest point of any of the polylines.

    Exact (segment distances), with a k-d tree over the vertices to limit the candidates: a
    segment nearer than the nearest vertex ``d`` has an end within ``d + longest segment``.

    Parameters
    ----------
    points : array_like, shape (n, 2)
    polylines : sequence of array_like, each shape (m_i, 2)
        Separate strokes (no segment joins one stroke to the next); a one-point stroke is a dot.

    Returns
    -------
    ndarray, shape (n,)
        ``inf`` everywhere if there are no polylines.
    """
    from scipy.spatial import cKDTree

    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    lines = [np.asarray(p, dtype=np.float64).reshape(-1, 2) for p in polylines]
    lines = [p for p in lines if len(p)]
    if not lines or not len(pts):
        return np.full(len(pts), np.inf)
    verts = np.concatenate(lines)
    stroke = np.concatenate([np.full(len(p), i) for i, p in enumerate(lines)])
    # segment j joins vertex j and j + 1 when both are in one stroke; else it is the dot at j
    nxt = np.minimum(np.arange(len(verts)) + 1, len(verts) - 1)
    nxt = np.where(stroke[nxt] == stroke, nxt, np.arange(len(verts)))
    a, b = verts, verts[nxt]
    longest = float(np.linalg.norm(b - a, axis=1).max())
    tree = cKDTree(verts)
    out = np.empty(len(pts))
    todo = np.arange(len(pts))
    k = min(16, len(verts))
    while len(todo):
        dist, idx = tree.query(pts[todo], k=k)
        dist, idx = dist.reshape(len(todo), -1), idx.reshape(len(todo), -1)
        cand = np.concatenate([idx, np.maximum(idx - 1, 0)], axis=1)  # segments at each vertex
        ca, cb = a[cand], b[cand]
        d = cb - ca
        u = ((pts[todo][:, None] - ca) * d).sum(-1) / np.maximum((d**2).sum(-1), 1e-30)
        foot = ca + np.clip(u, 0.0, 1.0)[..., None] * d
        best = np.linalg.norm(foot - pts[todo][:, None], axis=-1).min(axis=1)
        exact = (k >= len(verts)) | (dist[:, -1] >= dist[:, 0] + longest)
        out[todo[exact]] = best[exact]
        todo = todo[~exact]
        k = min(4 * k, len(verts))
    return out


def tracking_error(commanded: Sequence[ArrayLike], ink: Sequence[ArrayLike]) -> dict[str, float]:
    """Tracking error between the commanded pen-down strokes and the ink strokes (paper plane).

    Parameters
    ----------
    commanded : sequence of array_like, each shape (n_i, 2)
        Commanded pen-down strokes (cm).
    ink : sequence of array_like, each shape (m_j, 2)
        Ink strokes (cm).

    Returns
    -------
    dict
        ``mean_mm`` and ``max_mm`` over every commanded sample's distance to the ink and every
        ink point's distance to the command; ``command_to_ink_max_mm`` (missing or displaced
        ink) and ``ink_to_command_max_mm`` (stray ink) separately. ``inf`` when there is no ink.
    """
    cmd = np.concatenate([np.asarray(c, dtype=float).reshape(-1, 2) for c in commanded])
    inked = [np.asarray(s, dtype=float).reshape(-1, 2) for s in ink]
    to_ink = distance_to_polylines(cmd, inked)
    ink_pts = np.concatenate(inked) if inked else np.empty((0, 2))
    to_cmd = distance_to_polylines(ink_pts, commanded)
    both = np.concatenate([to_ink, to_cmd]) * 10.0
    return {
        "mean_mm": float(both.mean()),
        "max_mm": float(both.max()),
        "command_to_ink_max_mm": float(to_ink.max() * 10.0),
        "ink_to_command_max_mm": float(to_cmd.max() * 10.0) if len(to_cmd) else 0.0,
    }


def max_ink_gap(
    commanded: Sequence[ArrayLike], ink_points: ArrayLike, ink_stroke: ArrayLike
) -> float:
    """The longest stretch of a commanded stroke left without ink (cm).

    For each commanded stroke ``k``, its ink is the ink points tagged ``k`` (in time order):
    the gap is the largest of the distance from the stroke's start to its first ink point, the
    distances between consecutive ink points, and from the last ink point to the stroke's end.
    A stroke without any ink counts its whole length.

    Parameters
    ----------
    commanded : sequence of array_like, each shape (n_k, 2)
    ink_points : array_like, shape (m, 2)
        Every ink point, in time order.
    ink_stroke : array_like of int, shape (m,)
        Commanded stroke each ink point was made during (``-1``: none).

    Returns
    -------
    float
    """
    ink = np.asarray(ink_points, dtype=np.float64).reshape(-1, 2)
    tag = np.asarray(ink_stroke)
    worst = 0.0
    for k, stroke in enumerate(commanded):
        cmd = np.asarray(stroke, dtype=np.float64).reshape(-1, 2)
        mine = ink[tag == k]
        if not len(mine):
            worst = max(worst, float(arc_length(cmd)[-1]) if len(cmd) > 1 else math.inf)
            continue
        chain = np.concatenate([cmd[:1], mine, cmd[-1:]])
        worst = max(worst, float(np.linalg.norm(np.diff(chain, axis=0), axis=1).max()))
    return worst
