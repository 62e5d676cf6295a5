"""The arm's reachable workspace on the paper, and the refusal of a word that does not fit it.

:class:`ReachMap` is a grid over the sheet whose nodes are solved, on demand, by the IK (pen
vertical, from the rest pose, at every height the pen needs); :func:`check_workspace` refuses a
word that leaves the reachable cells with one line giving the largest size that fits (found by
bisection on the scale) and the ``scale=`` to set.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from prg.errors import UsageError
from prg.sim.geometry import Paper, bounding_box, place_points
from prg.sim.ik import IKSolver

__all__ = ["ReachMap", "check_workspace"]


class ReachMap:
    """Which points of the paper the pen tip reaches, vertical, at the heights it needs.

    Grid nodes ``step_cm`` apart cover the sheet; a node is reachable when the IK (from the rest
    pose) puts the tip there within tolerance, inside the joint limits, at every height in
    ``heights_cm``. Nodes are solved on demand and remembered. A point counts as reachable when
    the four nodes of its grid cell are (a conservative rule: the reachable region is the union
    of fully reachable cells).

    Parameters
    ----------
    ik : IKSolver
    paper : Paper
    heights_cm : sequence of float
        Tip heights above the paper to check (the surface and the lift height).
    step_cm : float
    """

    def __init__(
        self, ik: IKSolver, paper: Paper, heights_cm: tuple[float, ...], step_cm: float
    ) -> None:
        self.ik, self.paper, self.heights = ik, paper, tuple(heights_cm)
        half = np.asarray(paper.size_cm) / 2
        self.nx = max(1, math.ceil(2 * half[0] / step_cm))
        self.ny = max(1, math.ceil(2 * half[1] / step_cm))
        self.xs = np.linspace(-half[0], half[0], self.nx + 1)
        self.ys = np.linspace(-half[1], half[1], self.ny + 1)
        self._nodes: dict[tuple[int, int], bool] = {}

    @property
    def solved(self) -> int:
        """Number of grid nodes solved so far."""
        return len(self._nodes)

    def node(self, i: int, j: int) -> bool:
        """Whether grid node ``(xs[i], ys[j])`` is reachable (solved once)."""
        key = (i, j)
        if key not in self._nodes:
            tol = self.ik.settings.tolerance_mm / 1000.0
            ok = True
            for h in self.heights:
                target = self.paper.to_world([[self.xs[i], self.ys[j], h]])[0]
                _, err = self.ik.solve(target)
                ok = ok and err <= tol
                if not ok:
                    break
            self._nodes[key] = ok
        return self._nodes[key]

    def reachable(
        self, points_cm: NDArray[np.float64], stop_early: bool = False
    ) -> NDArray[np.bool_]:
        """Whether each point ``(x, y)`` (paper frame, cm) is on the sheet and reachable.

        With ``stop_early``, cells are solved only until the first unreachable one; the points
        of cells not examined then are reported unreachable (use it for an all-or-nothing test).
        """
        pts = np.asarray(points_cm, dtype=np.float64)[:, :2]
        out = np.zeros(len(pts), dtype=bool)
        on = self.paper.contains(pts)
        if stop_early and not on.all():
            return out
        i = np.clip(np.searchsorted(self.xs, pts[:, 0], side="right") - 1, 0, self.nx - 1)
        j = np.clip(np.searchsorted(self.ys, pts[:, 1], side="right") - 1, 0, self.ny - 1)
        cells, which = np.unique(np.column_stack([i, j])[on], axis=0, return_inverse=True)
        ok = np.zeros(len(cells), dtype=bool)
        for c, (a, b) in enumerate(cells.tolist()):
            ok[c] = all(self.node(a + da, b + db) for da in (0, 1) for db in (0, 1))
            if stop_early and not ok[c]:
                return out
        out[on] = ok[which.reshape(-1)]
        return out


def check_workspace(
    points_cm: NDArray[np.float64],
    anchor: NDArray[np.float64],
    target: NDArray[np.float64],
    scale: float,
    reach: ReachMap,
    robot: str,
    text: str,
) -> None:
    """Refuse a word that does not fit the reachable workspace on the paper.

    Parameters
    ----------
    points_cm : ndarray, shape (n, 2)
        The word's motion in its own frame (cm, unscaled).
    anchor, target : ndarray, shape (2,)
        The word's anchor (centre of its bounding box) and where it goes on the paper.
    scale : float
        The requested scale.
    reach : ReachMap
    robot, text : str
        For the message.

    Raises
    ------
    UsageError
        One line: the word's size, the largest size that fits (found by bisection on the scale
        about the same centre) and the ``scale=`` to set.
    """
    placed = place_points(points_cm, anchor, scale, target)
    ok = reach.reachable(placed)
    if ok.all():
        return

    def fits(s: float) -> bool:
        return bool(reach.reachable(place_points(points_cm, anchor, s, target), True).all())

    lo, hi = 0.0, scale
    for _ in range(14):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if fits(mid) else (lo, mid)
    low, high = bounding_box(points_cm)
    width, height = (high - low) * scale
    bad = placed[~ok][0]
    where = "off the paper" if not reach.paper.contains(bad[None])[0] else "out of reach"
    if lo <= 0:
        raise UsageError(
            f"word {text!r} cannot be written by {robot} at paper.word_centre_cm="
            f"[{target[0]:g},{target[1]:g}]: that point is {where}; move the word"
        )
    factor = math.floor(lo * 1000) / 1000
    raise UsageError(
        f"word {text!r} is {width:.1f} cm wide and {height:.1f} cm tall at scale={scale:g}, "
        f"and ({bad[0]:.1f}, {bad[1]:.1f}) cm on the paper is {where}; at most "
        f"{width * lo / scale:.1f} cm wide fits {robot}'s workspace on the "
        f"{reach.paper.size_cm[0]:g} x {reach.paper.size_cm[1]:g} cm paper: set "
        f"scale={factor:g} or smaller"
    )
