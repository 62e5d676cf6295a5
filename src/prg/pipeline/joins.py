"""Connection strokes that join letters as a hand does: they do not cut through the ink.

The paper's Algorithm 1 (:func:`prg.pipeline.connect.connect_letters`) steers the pen from the
end of a letter to the start of the next with bounded turns, but nothing keeps it off the ink:
over 40 everyday words written by the demo MUSE, 46 % of its connections crossed a letter away
from their ends ("little" read as "libble": the t ends at its foot and the connection climbs
back up through its stem; an ``o`` entered at its top from below reads as an ``a``).

:func:`hand_connection` keeps Algorithm 1's stroke when it crosses no ink, does not loop and
stays in the band the two letters span, and otherwise writes the stroke a writer would: among a
few smooth candidates — cubic curves leaving the letter along its last direction and entering
the next along its first, straight on, arched over the letters or dipping under the baseline,
from just clear of the two ends to well clear of all the ink between — the one that crosses no
ink (fewest crossings if none is clear), then one without a loop, then one that does not swing
above or below both letters (:func:`overshoot`), then the shortest and least turning.
Algorithm 1's bounded turns loop over an ``o`` left at its top heading left, and the highest
ink between two letters is often an ascender the stroke never passes (the arch of "lo" rose
over the l); a writer bridges to the next letter at the o's height instead. Candidates are
sampled every ``delta`` or less, so the connection keeps the no-gap guarantee of
:mod:`prg.pipeline.connect`. Where a letter ends, or the next one starts, on the far side of its
own ink, the writer lifts the pen instead (:func:`lifts_pen`), and so does
:func:`~prg.pipeline.connect.connect_sequence` where no candidate is clean (``lift=True``).

:func:`ink_crossings` is the measure: proper intersections of a connection with the letters'
ink, those within ``margin`` of the connection's two ends not counted (a stroke leaves and enters
ink there).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from prg.pipeline.connect import (
    ConnectionResult,
    ConnectionSettings,
    connect_letters,
    straight_connection,
)

#: Ink this close to a connection's ends (cm) is where it leaves and enters letters: not counted.
END_MARGIN = 0.1


def _segments_cross(a0, a1, b0, b1) -> np.ndarray:
    """Proper intersections of segments ``a0 a1`` (n, 2) with ``b0 b1`` (m, 2): (n, m) bool.

    Two segments cross when each one's ends lie strictly on opposite sides of the other's line
    (touching or collinear overlap does not count)."""

    def side(p, q, r):  # sign of the cross product (q - p) x (r - p), broadcast (n, m)
        return np.sign(
            (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1])
            - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0])
        )

    a0, a1 = a0[:, None, :], a1[:, None, :]
    b0, b1 = b0[None, :, :], b1[None, :, :]
    return (side(a0, a1, b0) * side(a0, a1, b1) < 0) & (side(b0, b1, a0) * side(b0, b1, a1) < 0)


def ink_crossings(path: np.ndarray, inks: Sequence[np.ndarray], margin: float = END_MARGIN) -> int:
    """How many times ``path`` crosses the ``inks`` away from its two ends.

    Parameters
    ----------
    path : ndarray, shape (k, 2)
        A connection from the end of one letter to the start of the next, both included.
    inks : sequence of ndarray, each shape (n_i, 2)
        The letters' strokes.
    margin : float
        Crossings closer than this to ``path[0]`` or ``path[-1]`` are not counted.

    Returns
    -------
    int

    Examples
    --------
    >>> stem = np.array([[1.0, -1.0], [1.0, 1.0]])
    >>> ink_crossings(np.array([[0.0, 0.0], [2.0, 0.0]]), [stem])
    1
    >>> ink_crossings(np.array([[0.0, 0.0], [0.95, 0.0]]), [stem])
    0
    """
    path = np.asarray(path, dtype=np.float64)
    if len(path) < 2:
        return 0
    ends = path[[0, -1]]
    low, high = path.min(0), path.max(0)
    total = 0
    for ink in inks:
        ink = np.asarray(ink, dtype=np.float64)
        if len(ink) < 2:
            continue
        a, b = ink[:-1], ink[1:]
        # only the ink segments whose boxes meet the path's box can cross it
        near_box = ((np.maximum(a, b) >= low) & (np.minimum(a, b) <= high)).all(axis=1)
        if not near_box.any():
            continue
        a, b = a[near_box], b[near_box]
        hits = _segments_cross(path[:-1], path[1:], a, b)
        if not hits.any():
            continue
        _, j = np.nonzero(hits)
        # where the two segments meet, roughly: the middle of the ink segment
        where = 0.5 * (a[j] + b[j])
        near = np.min(np.linalg.norm(where[:, None, :] - ends[None], axis=-1), axis=1)
        total += int((near > margin).sum())
    return total


def self_crossings(path: np.ndarray) -> int:
    """How many times ``path`` crosses itself (a loop in a connection reads as a letter).

    Examples
    --------
    >>> self_crossings(np.array([[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]]))
    1
    >>> self_crossings(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]))
    0
    """
    path = np.asarray(path, dtype=np.float64)
    if len(path) < 4:
        return 0
    hits = _segments_cross(path[:-1], path[1:], path[:-1], path[1:])
    return int(np.triu(hits, k=2).sum())


def overshoot(path: np.ndarray, prev: np.ndarray, nxt: np.ndarray) -> float:
    """How far ``path`` rises above both letters it joins, plus how far it dips below both (cm).

    A writer's connection stays in the band the two letters span; a stroke that swings over
    both (a loop over an ``o`` left at its top, an arch over an ascender it never passes) reads
    as a letter of its own.

    Examples
    --------
    >>> a, b = np.array([[0.0, 0.0], [0.0, 1.0]]), np.array([[1.0, 0.0], [1.0, 0.5]])
    >>> overshoot(np.array([[0.0, 1.0], [0.5, 1.25], [1.0, 0.5]]), a, b)
    0.25
    >>> overshoot(np.array([[0.0, 0.0], [0.5, -0.5], [1.0, 0.0]]), a, b)
    0.5
    """
    path, prev, nxt = (np.asarray(x, dtype=np.float64) for x in (path, prev, nxt))
    top = max(prev[:, 1].max(), nxt[:, 1].max())
    bottom = min(prev[:, 1].min(), nxt[:, 1].min())
    return float(max(0.0, path[:, 1].max() - top) + max(0.0, bottom - path[:, 1].min()))


def _direction(points: np.ndarray, from_end: bool) -> np.ndarray:
    """Unit direction of a letter's last (``from_end``) or first non-degenerate step."""
    steps = np.diff(points[::-1] if from_end else points, axis=0)
    steps = -steps if from_end else steps
    for step in steps if len(steps) else []:
        norm = math.hypot(*step)
        if norm > 1e-9:
            return step / norm
    return np.array([1.0, 0.0])


def _bezier_basis(t: np.ndarray) -> np.ndarray:
    """The cubic Bezier (Bernstein) basis at parameters ``t`` (n,): (n, 4)."""
    return np.stack([(1 - t) ** 3, 3 * (1 - t) ** 2 * t, 3 * (1 - t) * t**2, t**3], axis=1)


#: The curves are sampled at 400 parameters, then resampled at equal steps along their length.
_BEZIER = _bezier_basis(np.linspace(0.0, 1.0, 400))


def _cubics(controls: np.ndarray, delta: float) -> list[np.ndarray]:
    """For each cubic Bezier curve of ``controls`` (c, 4, 2), its points strictly between the
    first and the last control point, gaps <= ``delta`` (all curves evaluated at once)."""
    curves = _BEZIER @ controls  # (c, 400, 2)
    steps = np.linalg.norm(np.diff(curves, axis=1), axis=2)
    arcs = np.concatenate([np.zeros((len(curves), 1)), np.cumsum(steps, axis=1)], axis=1)
    out = []
    for curve, arc in zip(curves, arcs):
        n = max(1, math.ceil(arc[-1] / delta * 1.01))
        s = np.linspace(0.0, arc[-1], n + 1)[1:-1]
        out.append(
            np.column_stack([np.interp(s, arc, curve[:, 0]), np.interp(s, arc, curve[:, 1])])
        )
    return out


def arch_clearance(dist: float) -> float:
    """How far an arch clears the ink (cm), for ends ``dist`` apart: also how far a connection
    may pass above or below both letters (:func:`overshoot`) and still be in their band."""
    return 0.1 + 0.1 * dist


def _candidates(prev: np.ndarray, nxt: np.ndarray, inks, delta: float) -> list[np.ndarray]:
    """Smooth strokes from ``prev[-1]`` to ``nxt[0]`` (intermediate points only)."""
    p0, p3 = prev[-1], nxt[0]
    out_dir, in_dir = _direction(prev, True), _direction(nxt, False)
    dist = max(math.hypot(*(p3 - p0)), delta)
    # the ink between the two ends (in x, a little beyond): what an arch or a dip must clear
    every = np.concatenate([np.asarray(i, dtype=np.float64) for i in inks])
    low, high = min(p0[0], p3[0]) - 0.1, max(p0[0], p3[0]) + 0.1
    between = every[(every[:, 0] >= low) & (every[:, 0] <= high)]
    between = between if len(between) else np.stack([p0, p3])
    clearance = arch_clearance(dist)
    controls = [(p0, p0 + (p3 - p0) / 3, p3 - (p3 - p0) / 3, p3)]  # straight
    for reach in (0.15, 0.35, 0.7, 1.2):
        controls.append((p0, p0 + reach * dist * out_dir, p3 - reach * dist * in_dir, p3))
    top, bottom = between[:, 1].max(), between[:, 1].min()
    # from just over the higher end to well over the ink, and the same under: the lowest arch
    # that clears the ink is the one a writer draws (the ink between may be a tall letter's
    # ascender that the stroke never passes over)
    high_end, low_end = max(p0[1], p3[1]), min(p0[1], p3[1])
    levels = [
        *np.linspace(min(high_end, top) + clearance / 2, top + 2.5 * clearance, 6),
        *np.linspace(max(low_end, bottom) - clearance / 2, bottom - 2.5 * clearance, 6),
    ]
    for level in levels:
        # control points at the height that puts the curve's middle at ``level``
        height = (level - (p0[1] + p3[1]) / 8) / 0.75
        p1 = np.array([p0[0] + 0.3 * dist * out_dir[0], height])
        p2 = np.array([p3[0] - 0.3 * dist * in_dir[0], height])
        controls.append((p0, p1, p2, p3))  # arched over the ink, or dipping under it
    return _cubics(np.array(controls, dtype=np.float64), delta)


def _turning(path: np.ndarray) -> float:
    """The total absolute turning of a path (radians), its steps as complex numbers."""
    steps = np.diff(path[:, 0] + 1j * path[:, 1])
    steps = steps[np.abs(steps) > 1e-12]
    if len(steps) < 2:
        return 0.0
    return float(np.abs(np.angle(steps[1:] * steps[:-1].conj())).sum())


#: Letters a writer leaves from where they close, at the top (a cursive ``o``).
CLOSED_AT_TOP = "o"
#: The closure is the path's nearest return to its start in its second half, within this share
#: of the letter's height; what follows is cut when it descends more than ``CLOSED_DROP``.
CLOSED_NEAR = 0.35
CLOSED_DROP = 0.25


def closed_exit(points: np.ndarray) -> np.ndarray:
    """An ``o`` cut where it closes, at its top: the writer leaves it there.

    Some writers' ``o`` closes near its start, at the top, then goes down its right side into an
    exit at mid-height; joined to the next letter, that descent reads as an ``a``'s stem (the
    demo's robot wrote "joy" that read "jay"). When the path, in its second half, comes back to
    within ``CLOSED_NEAR`` of the letter's height of its start and then descends by more than
    ``CLOSED_DROP`` of it, the letter ends at that return; otherwise it is kept whole. Only a letter
    joined to the next one is cut (:func:`prg.pipeline.compose.compose_word`): a word's last o
    keeps its flourish.

    Parameters
    ----------
    points : ndarray, shape (n, 2)
        The letter, y up.

    Returns
    -------
    ndarray, shape (m, 2), m <= n
        A prefix of ``points``.
    """
    y = points[:, 1]
    height = float(np.ptp(y))
    half = len(points) // 2
    if height <= 0 or half < 2:
        return points
    distance = np.linalg.norm(points[half:] - points[0], axis=1)
    cut = half + int(np.argmin(distance))
    near = distance.min() < CLOSED_NEAR * height
    descends = y[cut:].min() < y[cut] - CLOSED_DROP * height
    return points[: cut + 1] if near and descends else points


#: A next letter starts on its far side when more than this share of its width lies left of its
#: start (a print s or d starts at its top right; a cursive o at its top middle is joined).
START_FAR = 2 / 3


def lifts_pen(prev: np.ndarray, nxt: np.ndarray, margin: float = END_MARGIN) -> bool:
    """Whether a writer lifts the pen between ``prev`` and ``nxt`` rather than join them.

    A letter that ends on the far side of its own ink from the next letter cannot be joined
    without going back over or around it: a print hand's ``j``, ``y``, ``g`` or ``p`` ends at
    the foot of its tail, left of its stem; an ``s`` or an ``x`` at its bottom left; a ``b`` at the
    foot of its stem, its bowl between the pen and the next letter. Joined, such a stroke arches
    over the letter or climbs back through it (the demo's print hands wrote "joy" with the j's foot
    joined over the j to the o). The same holds for a next letter that starts on its far side:
    a print ``s``, ``a``, ``d`` or ``g`` starts at its top right, and a stroke from the left
    reaches that start only around or through the letter. A person writing print lifts the pen
    there. The rule: the letter ends in its left half (more than half its width lies right of
    its end), or the next letter starts in its right third (:data:`START_FAR`), and the straight
    line from the end to the start crosses that letter's ink away from the line's two ends. A
    cursive letter that leaves towards the next one (a looped ``g`` that comes back up to the baseline and past its
    stem, an ``o`` left from its top) or starts towards the previous one (an ``o`` entered at
    its top left) does not, and is joined.

    Parameters
    ----------
    prev, nxt : ndarray, shape (n, 2)
        The letters before and after (laid out, centimetres).
    margin : float
        As :func:`ink_crossings`: ink this close to the line's ends is not counted.
    """
    prev = np.asarray(prev, dtype=np.float64)
    nxt = np.asarray(nxt, dtype=np.float64)
    line = np.stack([prev[-1], nxt[0]])
    left, right = prev[:, 0].min(), prev[:, 0].max()
    if right - prev[-1, 0] > 0.5 * (right - left) and ink_crossings(line, [prev], margin) > 0:
        return True
    left, right = nxt[:, 0].min(), nxt[:, 0].max()
    return nxt[0, 0] - left > START_FAR * (right - left) and ink_crossings(line, [nxt], margin) > 0


def hand_connection(
    prev: np.ndarray,
    nxt: np.ndarray,
    inks: Sequence[np.ndarray],
    params: ConnectionSettings | None = None,
    lift: bool = False,
) -> ConnectionResult:
    """A connection from ``prev[-1]`` to ``nxt[0]`` that crosses no ink when one can.

    Parameters
    ----------
    prev, nxt : ndarray, shape (n, 2)
        The letters before and after (laid out, centimetres).
    inks : sequence of ndarray
        The word's letters (``prev`` and ``nxt`` among them): the ink to stay off.
    params : ConnectionSettings, optional
    lift : bool
        When no stroke is clean (no ink crossed, no loop, in the band), lift the pen: the
        straight pen-up travel (``pen_up=True``), as a writer does who cannot join two letters.

    Returns
    -------
    ConnectionResult
        Algorithm 1's connection when it is clean; otherwise the candidate with the fewest ink
        crossings, then the fewest self-crossings, then one that stays in the band of the two
        letters (:func:`overshoot` at most an arch's clearance), then the least
        ``length / distance + turning / pi``. ``steered`` counts Algorithm 1's steered steps (0
        for a candidate curve).
    """
    params = params or ConnectionSettings()
    prev = np.asarray(prev, dtype=np.float64)
    nxt = np.asarray(nxt, dtype=np.float64)
    alg1 = connect_letters(prev, nxt, **params.as_kwargs())
    dist = max(math.hypot(*(nxt[0] - prev[-1])), params.delta)
    tolerance = arch_clearance(dist)

    def path_of(points):
        return np.concatenate([prev[-1:], points, nxt[:1]])

    def shape(points):  # (swings past both letters, length / distance + turning / pi): cheap
        path = path_of(points)
        length = float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())
        # the turns out of the letter and into the next count: a stroke that enters a stem
        # from below to write it downwards reverses there
        turns = _turning(np.concatenate([prev[-2:-1], path, nxt[1:2]]))
        return overshoot(path, prev, nxt) > tolerance, length / dist + turns / math.pi

    def crossings(points):  # (ink crossed, self-crossings): the costly part
        path = path_of(points)
        return ink_crossings(path, inks), self_crossings(path)

    if crossings(alg1.points) == (0, 0) and not shape(alg1.points)[0]:
        return alg1
    options = [alg1.points, *_candidates(prev, nxt, inks, params.delta)]
    shapes = [shape(points) for points in options]
    # the best clean stroke is the first in the band, in order of shape, that crosses nothing
    by_shape = sorted(range(len(options)), key=shapes.__getitem__)
    clean = (k for k in by_shape if not shapes[k][0] and crossings(options[k]) == (0, 0))
    best = next(clean, None)
    if best is None and lift:
        return dataclasses.replace(straight_connection(prev, nxt, params.delta), pen_up=True)
    if best is None:
        best = min(range(len(options)), key=lambda k: (*crossings(options[k]), *shapes[k]))
    if best == 0:
        return alg1
    return ConnectionResult(options[best], 0, 0, False)
