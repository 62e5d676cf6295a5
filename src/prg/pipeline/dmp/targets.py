"""Forcing-term targets: the forcing values a demonstration asks for, from finite differences.

The demonstration is taken on a uniform time grid over ``[0, tau]`` (``n`` points);
velocities and accelerations come from five-point (fourth-order) finite differences
(one-sided near the ends). The target forcing values ``F = (tau^2 y'' + D tau y') / K - (g_m(t) -
y) + (g - y0) x - D tau g' / K`` (``y0`` the first point, ``g`` the last, ``g'`` zero or the last
point's velocity) are what :func:`~prg.pipeline.dmp.regression.fit_dmp` regresses on the
design matrix.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numpy.typing import ArrayLike

from prg.pipeline.dmp.canonical import phase
from prg.pipeline.dmp.settings import ALPHA_X, DAMPING, STIFFNESS, _FloatArray
from prg.pipeline.dmp.validation import _nonnegative, _points, _positive, _velocities

_FD_POINTS = 5  # finite-difference stencil (fourth order)


@functools.lru_cache(maxsize=16)
def _stencils(width: int, order: int) -> _FloatArray:
    """Finite-difference weights on ``width`` consecutive samples (unit spacing), one row per
    position ``o`` of the sample within them: ``sum_j w[o, j] y_j ~ y^(order)`` at sample ``o``."""
    table = np.empty((width, width))
    rhs = np.zeros(width)
    rhs[order] = math.factorial(order)
    for o in range(width):
        nodes = np.arange(width, dtype=np.float64) - o
        table[o] = np.linalg.solve(np.vander(nodes, width, increasing=True).T, rhs)
    table.setflags(write=False)
    return table


def _derivative(y: _FloatArray, step: float, order: int) -> _FloatArray:
    """``order``-th time derivative of samples ``y`` (n, dims) ``step`` apart, five-point stencils.

    Centred in the interior (fourth order), one-sided within two samples of either end; with fewer
    than five samples the stencil covers all of them.
    """
    n = y.shape[0]
    width = min(_FD_POINTS, n)
    half = width // 2
    table = _stencils(width, order)
    inner = n - width + 1  # samples with a centred stencil: half .. half + inner - 1
    out = np.empty_like(y)
    out[half : half + inner] = sum(table[half, j] * y[j : j + inner] for j in range(width))
    out[:half] = table[:half] @ y[:width]
    out[half + inner :] = table[half + 1 :] @ y[n - width :]
    out /= step**order
    return out


def forcing_targets(
    points: ArrayLike,
    tau: float = 1.0,
    stiffness: float = STIFFNESS,
    damping: float = DAMPING,
    alpha_x: float = ALPHA_X,
    velocities: str = "rest",
) -> tuple[_FloatArray, _FloatArray]:
    """Phase and target forcing values of a demonstration on a uniform grid over ``[0, tau]``.

    Parameters
    ----------
    points : array_like, shape (n, dims)
        The demonstration, ``n >= 3`` finite points, ``tau / (n - 1)`` apart in time.
    tau : float
        Its duration, > 0.
    stiffness, damping, alpha_x : float
        ``K > 0``, ``D >= 0`` and ``alpha_x > 0`` of the DMP.
    velocities : {"rest", "demonstrated"}
        The goal velocity ``g'``: zero, or the demonstration's last velocity (:func:`fit_dmp`).

    Returns
    -------
    x : ndarray, shape (n,)
        Phase at the samples.
    targets : ndarray, shape (n, dims)
        ``(tau^2 y'' + D tau y') / K - (g_m(t) - y) + (g - y0) x - D tau g' / K``, with ``y'``
        and ``y''`` from five-point finite differences of the positions (centred, one-sided at
        the ends).
    """
    y = _points(points)
    tau = _positive(tau, "tau")
    stiffness = _positive(stiffness, "stiffness")
    damping = _nonnegative(damping, "damping")
    alpha_x = _positive(alpha_x, "alpha_x")
    x, targets, _, _ = _targets(y, tau, stiffness, damping, alpha_x, _velocities(velocities))
    return x, targets


def _targets(
    y: _FloatArray,
    tau: float,
    stiffness: float,
    damping: float,
    alpha_x: float,
    demonstrated: bool,
) -> tuple[_FloatArray, _FloatArray, _FloatArray, _FloatArray]:
    """:func:`forcing_targets` on validated arguments, and the start and goal velocities (per
    second: the demonstration's first and last when ``demonstrated``, else zeros).

    Computed on ``y - y0``: the targets depend on the positions only through differences, and
    finite differences of absolute coordinates would round at the size of the coordinates, which
    the stencils amplify by ``(n - 1)^2`` (a path far from the origin was reproduced with an error
    of ~1e4 ulps of its offset; a nearly constant one, 1e-9 cm around 1e4 cm, 70 of its steps).
    """
    n = y.shape[0]
    dt = tau / (n - 1)
    rel = y - y[0]
    yd = _derivative(rel, dt, 1)
    ydd = _derivative(rel, dt, 2)
    t = np.arange(n) * dt
    x = phase(t, tau, alpha_x)
    goal = rel[-1]
    start_velocity = yd[0] if demonstrated else np.zeros_like(goal)
    goal_velocity = yd[-1] if demonstrated else np.zeros_like(goal)
    targets = (tau**2 * ydd + damping * tau * yd) / stiffness - (goal - rel) + np.outer(x, goal)
    if demonstrated:  # the moving goal g_m(t) = g - g' (tau - t) and the damping of tau g'
        targets += np.outer(tau - t, goal_velocity) - damping * tau * goal_velocity / stiffness
    return x, targets, start_velocity, goal_velocity
