"""Connection strokes between consecutive letters: the paper's Algorithm 1 and the straight joiner.

The last step of the final processing map (paper, appendix "Final Processing Map") joins the end
of letter ``i`` to the start of letter ``i + 1`` with an intermediate trajectory, so that the word
is one pen-down motion. :func:`connect_letters` implements the paper's Algorithm 1;
:func:`straight_connection` is the straight-line joiner the paper compares against ("abrupt
changes when transitioning between succeeding letter trajectories").

Reading of Algorithm 1
----------------------
The pseudo-code is loose: ``c`` is initialised to a direction vector (the last segment of letter
``i``) but then used as a point, the candidate direction is built from ``cos(alpha)`` alone (which
loses the sign of the turn), the angle of a *point* of letter ``i + 1`` is taken against the x axis
rather than the angle of the vector from the pen to it, and the stop test
``until ||x[j] - c|| > delta`` reads inverted (the loop would stop after one step). The prose and the
figure that illustrates the algorithm make the intent clear; this module implements that intent:

* The pen starts at the last point of letter ``i`` with the heading of that letter's last
  segment (the last non-degenerate one; towards letter ``i + 1``'s first point if the letter has
  no extent).
* Each iteration makes **one candidate per point** ``j`` of letter ``i + 1`` (``m`` points): the
  heading turned towards point ``j``, the turn clipped to ``[-alpha_max, alpha_max]``, and the
  candidate is the pen moved ``delta`` along that heading.
* Each candidate's cost is ``theta_o * j / m + theta_a * A_j + theta_f * F_j + theta_p * P_j``
  where ``A_j`` is the absolute turn, ``F_j`` the candidate's distance to letter ``i + 1``'s
  first point and ``P_j`` its distance to its own target point ``j``; ``A``, ``F`` and ``P`` are
  min-max normalised over the candidates as in the paper (a term whose range is zero, e.g. when
  every turn is clipped to the same value, contributes 0).
* The cheapest candidate becomes the next point of the connection, and the loop ends when the pen
  is within ``delta`` of its target (the paper's stop test, with the comparison the right way
  round; which target counts is decided by ``join``, below).

Two additions make the loop terminate on real letters (measured on random lowercase pairs of the
synthetic test split: with neither, 43 of 200 connections ran out of steps, orbiting a target):

* **Orbit rule**: with steps of ``delta`` turning at most ``alpha_max``, the pen's tightest turn
  has radius ``R = delta / (2 sin(alpha_max / 2))``; a target inside that circle on the side it
  lies on can never be reached by turning towards it (the pen circles it for ever). Such a
  candidate goes straight on instead, which widens the turn into a loop that does reach it.
* **Homing**: once the pen comes within ``home_radius`` of letter ``i + 1``'s first point it
  keeps only that point's candidate (it stops weighing the other points). Far from the letter,
  the four-term cost shapes the path; near it, the pen aims. Homing never switches back off.

With both, no connection of the 300 needs the fallback below; ``home_radius = 0`` gives the
unmodified candidate competition (``connection.home_radius=0``: :func:`connect_letters` and the
command accept the same values, those :class:`ConnectionSettings` declares).

Every point of letter ``i + 1`` is still written, in order
-----------------------------------------------------------
In the paper the chosen target ``j`` can be any point of letter ``i + 1``, so joining at ``j > 0``
would skip the letter's first ``j`` points. Two honest repairs are offered (``join``):

* ``"first"`` (default): the candidates towards every point ``j`` shape the path (the index,
  angle and distance terms decide which way the pen bends), but only letter ``i + 1``'s **first
  point** ends the connection. The letter is then written whole from its start. This is how
  cursive hands join letters (the connecting stroke runs into the letter's entry point), the
  motion never reverses, and on the project's letters it gives the smoothest joins.
* ``"retrace"``: the paper's stop test on the chosen ``j``; when ``j > 0`` the connection joins
  the letter at point ``j`` and then runs back along the letter (points ``j``, ``j - 1``, ...,
  ``1``, subdivided at ``delta``) to its first point, from which the letter is written whole.
  The ink of the return lies on the letter itself, but the pen reverses at point ``j``.

Guarantees (tested in ``tests/prg/pipeline/test_connect.py``)
-------------------------------------------------------------
With ``P = [prev[-1], *result.points, nxt[0]]``:

1. **Termination**: at most ``max_steps`` steered steps. If the target is not reached by then
   (it can lie inside the pen's turning circle, radius ``delta / (2 sin(alpha_max / 2))``, and be
   orbited forever), the steered path is cut at its point closest to the target and finished by a
   straight segment subdivided at ``delta``; ``result.fallback`` is True.
2. **No gap**: every consecutive distance in ``P`` is at most ``delta`` (the final join too),
   up to the rounding of the coordinates (relative 1e-12).
3. **Bounded turning**: the first ``result.steered`` points of the connection are steered steps of
   length exactly ``delta``; the heading change between consecutive segments of
   ``[prev[-2], prev[-1], *result.points[:steered]]`` is at most ``alpha_max`` (the first one is
   measured against the direction of ``prev``'s last non-degenerate segment). Not covered: the
   final join (one segment shorter than ``delta`` into the target), the straight fallback tail,
   the ``"retrace"`` return, and the entry into letter ``i + 1`` itself.
4. **Every point of the next letter is written, in order**: the connection ends within
   ``delta`` of ``nxt[0]`` in both modes and the word then writes ``nxt`` whole from ``nxt[0]``;
   no point of ``nxt`` is dropped or reordered (``"first"`` never passes ``nxt``'s points as
   its own; ``"retrace"`` runs over ``nxt[j:0:-1]`` backwards, then ``nxt`` is written forwards).

All lengths are in the units of the inputs (centimetres in the pipeline), angles in radians.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from prg.errors import UsageError
from prg.pipeline.settings import ConnectionSettings, JoinMode  # exported here too

_TINY = 1e-12
_DEFAULT = ConnectionSettings()


@dataclass(frozen=True)
class ConnectionResult:
    """A connection between two letters.

    Attributes
    ----------
    points : ndarray, shape (k, 2)
        The intermediate points, strictly between ``prev[-1]`` and ``nxt[0]`` (both excluded), so
        that ``prev``, ``points``, ``nxt`` concatenated is the pen-down path; ``k`` may be 0 when
        the letters are already within ``delta``.
    steered : int
        How many leading ``points`` are steered steps (length ``delta``, turn <= ``alpha_max``).
    target : int
        Index of the next letter's point where the steered path joined it (0 for ``"first"``,
        the straight joiner and the fallback).
    fallback : bool
        True when ``max_steps`` ran out and the connection was finished by a straight segment.
    pen_up : bool
        True for a pen-up travel (a straight path, no ink): between words, or where a writer
        lifts the pen within one (:func:`prg.pipeline.joins.lifts_pen`).
    """

    points: np.ndarray
    steered: int
    target: int
    fallback: bool
    pen_up: bool = False


def _check_points(points, name: str) -> np.ndarray:
    arr = np.asarray(points, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] < 1:
        raise UsageError(f"{name} must have shape (n, 2) with n >= 1, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise UsageError(f"{name} contains NaN or infinite values")
    return arr


def subdivide(start: np.ndarray, end: np.ndarray, delta: float) -> np.ndarray:
    """Points strictly between ``start`` and ``end`` on the straight segment, gaps <= ``delta``.

    Parameters
    ----------
    start, end : ndarray, shape (2,)
    delta : float
        Largest gap, > 0.

    Returns
    -------
    ndarray, shape (k, 2)
        ``k = ceil(|end - start| / delta) - 1`` equally spaced points (0 when the ends are within
        ``delta``); the gap is ``|end - start| / (k + 1)``.
    """
    start = np.asarray(start, dtype=np.float64)
    end = np.asarray(end, dtype=np.float64)
    dist = float(np.hypot(*(end - start)))
    n = max(1, math.ceil(dist / delta))
    # ceil can round down by one ulp's worth of ratio; one more piece keeps every gap <= delta
    if dist / n > delta:
        n += 1
    t = np.arange(1, n, dtype=np.float64)[:, None] / n
    return start + t * (end - start)


def _densify(path: np.ndarray, delta: float) -> np.ndarray:
    """``path`` with points inserted so every gap is <= ``delta`` (all original points kept)."""
    out = [path[:1]]
    for a, b in itertools.pairwise(path):
        out.append(subdivide(a, b, delta))
        out.append(b[None])
    return np.concatenate(out, axis=0)


def straight_connection(prev, nxt, delta: float = _DEFAULT.delta) -> ConnectionResult:
    """The straight-line joiner: ``prev[-1]`` to ``nxt[0]`` with a point every <= ``delta``.

    Parameters
    ----------
    prev : ndarray, shape (n, 2)
        The letter written before (only its last point matters).
    nxt : ndarray, shape (m, 2)
        The letter written after (only its first point matters).
    delta : float
        Largest gap, > 0.

    Returns
    -------
    ConnectionResult
        ``steered = 0``, ``target = 0``, ``fallback = False``.
    """
    prev = _check_points(prev, "prev")
    nxt = _check_points(nxt, "nxt")
    delta = ConnectionSettings(delta=delta).delta
    return ConnectionResult(subdivide(prev[-1], nxt[0], delta), 0, 0, False)


def _initial_heading(prev: np.ndarray, towards: np.ndarray) -> float:
    """Angle of ``prev``'s last non-degenerate segment; towards ``towards`` if there is none."""
    steps = np.diff(prev, axis=0)
    lengths = np.hypot(steps[:, 0], steps[:, 1])
    moving = np.flatnonzero(lengths > _TINY)
    d = steps[moving[-1]] if moving.size else towards - prev[-1]
    return math.atan2(d[1], d[0])


def _minmax(values: np.ndarray, weight: float) -> np.ndarray:
    """``weight`` times ``values`` min-max normalised to [0, 1]; a (near) zero range gives
    zeros."""
    lo = values.min()
    span = values.max() - lo
    if not span > 1e-12 * max(1.0, abs(lo)):
        return np.zeros_like(values)
    return (values - lo) * (weight / span)


def connect_letters(
    prev,
    nxt,
    delta: float = _DEFAULT.delta,
    alpha_max: float = _DEFAULT.alpha_max,
    theta_o: float = _DEFAULT.theta_o,
    theta_a: float = _DEFAULT.theta_a,
    theta_f: float = _DEFAULT.theta_f,
    theta_p: float = _DEFAULT.theta_p,
    home_radius: float = _DEFAULT.home_radius,
    max_steps: int = _DEFAULT.max_steps,
    join: JoinMode = _DEFAULT.join,
) -> ConnectionResult:
    """Connect the end of ``prev`` to the start of ``nxt`` with Algorithm 1 (module docstring).

    Parameters
    ----------
    prev : ndarray, shape (n, 2)
        Letter ``i`` (its last point is the start; its last segment the initial heading).
    nxt : ndarray, shape (m, 2)
        Letter ``i + 1`` (one candidate per point).
    delta, alpha_max, theta_o, theta_a, theta_f, theta_p, home_radius, max_steps, join
        See :class:`ConnectionSettings` (defaults from there).

    Returns
    -------
    ConnectionResult
        Intermediate points strictly between ``prev[-1]`` and ``nxt[0]``; guarantees in the
        module docstring.

    Raises
    ------
    UsageError
        A malformed array or a parameter :class:`ConnectionSettings` refuses (a
        :class:`~prg.errors.SettingsError` naming it): the function accepts what the config
        accepts, ``home_radius = 0`` (no homing) and ``max_steps = 0`` (the straight joiner)
        included.
    """
    prev = _check_points(prev, "prev")
    nxt = _check_points(nxt, "nxt")
    params = ConnectionSettings(  # the parameters' one check: the config's ranges
        delta, alpha_max, theta_o, theta_a, theta_f, theta_p, home_radius, max_steps, join
    )
    delta, alpha_max, theta_o, theta_a = (
        params.delta,
        params.alpha_max,
        params.theta_o,
        params.theta_a,
    )
    theta_f, theta_p, home_radius, max_steps = (
        params.theta_f,
        params.theta_p,
        params.home_radius,
        params.max_steps,
    )

    start, first = prev[-1], nxt[0]
    m = nxt.shape[0]
    index_term = theta_o * np.arange(m, dtype=np.float64) / m
    target_x, target_y = np.ascontiguousarray(nxt[:, 0]), np.ascontiguousarray(nxt[:, 1])
    first_x, first_y = float(first[0]), float(first[1])
    radius = delta / (2 * math.sin(alpha_max / 2))  # of the pen's tightest turn
    half_pi = math.pi / 2
    pen_x, pen_y = float(start[0]), float(start[1])
    homing = False
    heading = _initial_heading(prev, first)
    path: list[tuple[float, float]] = []
    joined = 0 if math.hypot(first_x - pen_x, first_y - pen_y) <= delta else -1
    while joined < 0 and len(path) < max_steps:
        homing = homing or math.hypot(first_x - pen_x, first_y - pen_y) < home_radius
        if homing:
            # one candidate, the first point: its cost terms are all zero, so it is taken;
            # the same step as below, in scalars (a third to a half of the steps)
            wanted = (math.atan2(first_y - pen_y, first_x - pen_x) - heading + math.pi) % (
                2 * math.pi
            ) - math.pi
            turn = min(max(wanted, -alpha_max), alpha_max)
            if abs(wanted) > alpha_max:
                arc = heading + turn / 2 + math.copysign(half_pi, wanted)
                centre_x = pen_x + radius * math.cos(arc)
                centre_y = pen_y + radius * math.sin(arc)
                if math.hypot(first_x - centre_x, first_y - centre_y) < radius:
                    turn = 0.0  # orbiting: go straight on
            heading += turn
            pen_x += delta * math.cos(heading)
            pen_y += delta * math.sin(heading)
            path.append((pen_x, pen_y))
            if math.hypot(pen_x - first_x, pen_y - first_y) <= delta:
                joined = 0
            continue
        to_x, to_y = target_x - pen_x, target_y - pen_y
        bearing = np.arctan2(to_y, to_x)
        wanted = np.remainder(bearing - heading + np.pi, 2 * np.pi) - np.pi
        turn = np.minimum(np.maximum(wanted, -alpha_max), alpha_max)
        # a target inside the turning circle on its side would be orbited: go straight on.
        # Only a target within the circle's diameter of the pen can be inside it.
        near = np.flatnonzero(
            (np.abs(wanted) > alpha_max) & (np.hypot(to_x, to_y) < 2.000001 * radius)
        )
        if near.size:
            arc = heading + turn[near] / 2 + np.sign(wanted[near]) * half_pi
            centre_x = pen_x + radius * np.cos(arc)
            centre_y = pen_y + radius * np.sin(arc)
            orbit = np.hypot(target_x[near] - centre_x, target_y[near] - centre_y) < radius
            turn[near[orbit]] = 0.0
        angles = heading + turn
        cand_x = pen_x + delta * np.cos(angles)  # (m,)
        cand_y = pen_y + delta * np.sin(angles)
        dist_first = np.hypot(cand_x - first_x, cand_y - first_y)
        dist_own = np.hypot(cand_x - target_x, cand_y - target_y)
        np.abs(turn, out=turn)
        cost = index_term + _minmax(turn, theta_a)
        cost += _minmax(dist_first, theta_f)
        cost += _minmax(dist_own, theta_p)
        j = int(np.argmin(cost))
        pen_x, pen_y, heading = float(cand_x[j]), float(cand_y[j]), float(angles[j])
        path.append((pen_x, pen_y))
        if dist_first[j] <= delta:
            joined = 0
        elif join == "retrace" and dist_own[j] <= delta:
            joined = j

    steered = np.asarray(path, dtype=np.float64).reshape(-1, 2)
    if joined < 0:  # max_steps ran out: cut at the closest approach, finish straight
        if steered.shape[0]:
            gaps = np.hypot(steered[:, 0] - first[0], steered[:, 1] - first[1])
            keep = int(np.argmin(gaps)) + 1
            if float(np.hypot(*(start - first))) <= gaps[keep - 1]:
                keep = 0
            steered = steered[:keep]
        tail_from = steered[-1] if steered.shape[0] else start
        tail = subdivide(tail_from, first, delta)
        return ConnectionResult(np.concatenate([steered, tail]), steered.shape[0], 0, True)
    if joined == 0:
        return ConnectionResult(steered, steered.shape[0], 0, False)
    # "retrace": join at point j (within delta of the pen), run back along the letter to point 1
    back = _densify(np.concatenate([steered[-1:], nxt[joined::-1]]), delta)[1:-1]
    return ConnectionResult(np.concatenate([steered, back]), steered.shape[0], joined, False)


def connection_path(prev, result: ConnectionResult, nxt) -> np.ndarray:
    """``[prev[-1], *result.points, nxt[0]]``: the pen path the guarantees are stated on.

    Returns
    -------
    ndarray, shape (k + 2, 2)
    """
    prev = np.asarray(prev, dtype=np.float64)
    nxt = np.asarray(nxt, dtype=np.float64)
    return np.concatenate([prev[-1:], result.points, nxt[:1]], axis=0)


def connect_sequence(
    letters,
    params: ConnectionSettings | None = None,
    method: Literal["hand", "alg1", "straight"] = "alg1",
    breaks=None,
) -> list[ConnectionResult]:
    """Connections between every pair of consecutive letters.

    Parameters
    ----------
    letters : sequence of ndarray, each shape (n_i, 2)
        Letters in writing order, already laid out (centimetres).
    params : ConnectionSettings, optional
        Defaults to ``ConnectionSettings()``.
    method : {"hand", "alg1", "straight"}
        :func:`prg.pipeline.joins.hand_connection` (Algorithm 1 unless it cuts through ink),
        :func:`connect_letters` or :func:`straight_connection` (which uses only ``params.delta``).
    breaks : sequence of bool, optional
        One per pair (:func:`prg.pipeline.layout.word_breaks`): True where a space separates the
        two letters. Those pairs get the straight pen-up travel (subdivided at ``delta``)
        whatever ``method`` is; with ``"hand"``, so do the pairs where a writer lifts the pen
        (:func:`prg.pipeline.joins.lifts_pen`).

    Returns
    -------
    list of ConnectionResult, length ``len(letters) - 1``
    """
    params = params or ConnectionSettings()
    if method not in ("hand", "alg1", "straight"):
        raise UsageError(f"method must be 'hand', 'alg1' or 'straight', got {method!r}")
    n_pairs = max(len(letters) - 1, 0)
    breaks = [False] * n_pairs if breaks is None else list(breaks)
    if len(breaks) != n_pairs:
        raise UsageError(
            f"breaks must have one entry per letter pair ({n_pairs}), got {len(breaks)}"
        )
    out = []
    if method == "hand":
        from prg.pipeline.joins import hand_connection, lifts_pen
    for a, b, pen_up in zip(letters[:-1], letters[1:], breaks):
        if pen_up or (method == "hand" and lifts_pen(a, b)):
            out.append(dataclasses.replace(straight_connection(a, b, params.delta), pen_up=True))
        elif method == "hand":
            out.append(hand_connection(a, b, letters, params, lift=True))
        elif method == "alg1":
            out.append(connect_letters(a, b, **params.as_kwargs()))
        else:
            out.append(straight_connection(a, b, params.delta))
    return out
