"""Rolling a DMP out: its positions over ``[0, tau]``, integrated exactly, without a Python loop.

**Rollout** (:func:`rollout`): the phase has a closed form, so the input ``u(t) = (g - y0)(1 - x) +
f(x) - g' (tau - t) + D tau g' / K`` is a known function of time and ``e = y - y0`` obeys the
linear time-invariant ODE ``tau^2 e'' + D tau e' + K e = K u``, started at ``e'(0) = y0'``: the
response to the input from rest plus the free response to that start velocity (the same
recurrence, one extra term in its first step). It is discretised exactly for an input that is the
cubic through the four nearest samples (one matrix exponential), and the resulting two-pole
recurrence is solved as one banded lower-triangular system (LAPACK ``tbtrs``, forward
substitution, the same arithmetic as an all-pole ``lfilter``; ``scipy.signal`` itself costs a
generating command half a second of import); there is no per-step Python loop. The only
approximation is that cubic interpolation of ``u``; when fewer than ``samples_per_basis``
(default ``SAMPLES_PER_BASIS``) output samples per basis function are asked for, the rollout
runs on a finer grid and is subsampled. In
time ``t / tau`` the system does not depend on ``tau``, so changing the tempo only stretches time:
the same number of samples gives the same path.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike

from prg.errors import UsageError
from prg.pipeline.dmp.basis import _forcing
from prg.pipeline.dmp.model import DMP
from prg.pipeline.dmp.settings import SAMPLES_PER_BASIS, _FloatArray
from prg.pipeline.dmp.threads import _one_blas_thread
from prg.pipeline.dmp.validation import _count, _positive, _vector

_HOLD_POINTS = 4  # samples of the input interpolated on each rollout step (cubic)


@functools.lru_cache(maxsize=64)
def _hold(
    stiffness: float, damping: float, step: float, points: int
) -> tuple[_FloatArray, _FloatArray]:
    """Exact discretisation of ``e'' + D e' + K e = K u`` for ``u`` a polynomial between samples.

    Time is in units of ``tau``. On each step, ``u`` is the polynomial through ``points``
    consecutive samples; which ones depends on the step's place (centred in the interior).

    Returns
    -------
    transition : ndarray, shape (2, 2)
        ``state[k+1] = transition @ state[k] + sum_j gains[o, :, j] u[start + j]``, state
        ``(e, e')``.
    gains : ndarray, shape (points - 1, 2, points)
        For each offset ``o = k - start`` of the step within its samples.
    """
    degree = points - 1
    size = 3 + degree
    generator = np.zeros((size, size))
    generator[:2, :2] = [[0.0, 1.0], [-stiffness, -damping]]
    generator[1, 2] = stiffness
    generator[np.arange(2, size - 1), np.arange(3, size)] = 1.0  # r^m / m! chain
    block = scipy.linalg.expm(generator * step)
    # moments[:, m] = integral_0^h e^{A (h - r)} B (r / h)^m dr
    moments = block[:2, 2:] * (
        np.array([math.factorial(m) for m in range(points)]) / step ** np.arange(points)
    )
    gains = []
    for offset in range(points - 1):
        nodes = np.arange(points, dtype=np.float64) - offset
        # Lagrange basis through the nodes: l_j(s) = sum_m inv(V)[m, j] s^m
        gains.append(moments @ np.linalg.inv(np.vander(nodes, points, increasing=True)))
    transition, gains = block[:2, :2].copy(), np.array(gains)
    transition.setflags(write=False)  # cached (a rollout per word of the same length)
    gains.setflags(write=False)
    return transition, gains


def _response(
    u: _FloatArray, stiffness: float, damping: float, start_slope: _FloatArray
) -> _FloatArray:
    """``e`` at the samples of ``u`` (n, dims), uniform over ``s = t / tau`` in [0, 1], from
    ``e(0) = 0`` and ``de/ds(0) = start_slope`` (dims,)."""
    n = u.shape[0]
    points = min(_HOLD_POINTS, n)
    transition, gains = _hold(stiffness, damping, 1.0 / (n - 1), points)
    k = np.arange(n - 1)
    start = np.clip(k - (points // 2 - 1), 0, n - points)
    window = u[start[:, None] + np.arange(points)]  # (n - 1, points, dims)
    drive = np.einsum("kij,kjd->kid", gains[k - start], window)  # state input of each step
    # e = C (zI - transition)^-1 drive, as one all-pole filter on the combined input
    combined = np.zeros_like(u)
    combined[1:] = drive[:, 0]
    combined[2:] += transition[0, 1] * drive[:-1, 1] - transition[1, 1] * drive[:-1, 0]
    # the free response to the start slope, (transition^k (0, slope))[0], obeys the same
    # recurrence with this single term (its z-transform's numerator is transition[0, 1] z)
    combined[1] += transition[0, 1] * start_slope
    # e[k] - trace e[k-1] + det e[k-2] = combined[k], from rest: unit lower-triangular, 2 sub-diagonals
    bands = np.empty((3, n))
    bands[0] = 1.0
    bands[1] = -np.trace(transition)
    bands[2] = np.linalg.det(transition)
    response, info = scipy.linalg.lapack.dtbtrs(bands, combined, uplo="L", diag="U")
    if info != 0:  # unreachable: the diagonal is all ones
        raise ArithmeticError(f"banded solve failed (LAPACK info {info})")
    return response


def rollout(
    dmp: DMP,
    n_samples: int | None = None,
    y0: ArrayLike | None = None,
    goal: ArrayLike | None = None,
    tau: float | None = None,
    *,
    dt: float | None = None,
    start_velocity: ArrayLike | None = None,
    goal_velocity: ArrayLike | None = None,
    samples_per_basis: int = SAMPLES_PER_BASIS,
) -> _FloatArray:
    """Positions of the DMP over ``[0, tau]``, computed without a per-step Python loop.

    Parameters
    ----------
    dmp : DMP
        As from :func:`fit_dmp`.
    n_samples : int, optional
        Number of output samples, >= 2, uniform over ``[0, tau]``; default ``dmp.n_samples``.
        Not together with ``dt``.
    y0 : array_like, shape (dims,), optional
        New start; default ``dmp.y0``.
    goal : array_like, shape (dims,), optional
        New goal; default ``dmp.goal``.
    tau : float, optional
        New duration (tempo), > 0; default ``dmp.tau``. With the same number of samples the
        path is the same; only the time between samples changes.
    dt : float, optional
        Time step instead of ``n_samples``, > 0: ``round(tau / dt) + 1`` samples (at least 2), so
        the step is ``dt`` up to the rounding of ``tau / dt``.
    start_velocity, goal_velocity : array_like, shape (dims,), optional
        New start velocity ``y0'`` and goal velocity ``g'`` (per second); default the DMP's.
    samples_per_basis : int
        Least number of integration samples per basis function, >= 1: with fewer output
        samples than that, the rollout integrates on a finer grid and subsamples it. On words
        fitted with 70 basis functions per 100 samples, against 16 per basis function, the
        default leaves at most 0.1 um and 1 (the output grid itself) at most 5 um
        (:func:`prg.pipeline.compose.compose_word`).

    Returns
    -------
    ndarray, shape (n_samples, dims)
        ``y(t_k)`` at ``t_k = k tau / (n_samples - 1)``; row 0 is ``y0``.

    Examples
    --------
    The same movement towards another goal: the shape is kept, the end moves.

    >>> import numpy as np
    >>> from prg.pipeline.dmp import fit_dmp, rollout
    >>> t = np.linspace(0, 1, 201)
    >>> s = 10 * t**3 - 15 * t**4 + 6 * t**5
    >>> dmp = fit_dmp(np.column_stack([s, np.sin(np.pi * s)]), tau=2.0, n_basis=40)
    >>> path = rollout(dmp, n_samples=201, goal=[2.0, 0.0])
    >>> path.shape
    (201, 2)
    >>> path[0].tolist(), bool(np.allclose(path[-1], [2.0, 0.0], atol=0.05))
    ([0.0, 0.0], True)
    """
    if not isinstance(dmp, DMP):
        raise UsageError(f"dmp: expected a DMP, got {type(dmp).__name__}")
    dims = dmp.dims
    start = dmp.y0 if y0 is None else _vector(y0, "y0", dims)
    end = dmp.goal if goal is None else _vector(goal, "goal", dims)
    tau = dmp.tau if tau is None else _positive(tau, "tau")
    start_vel = (
        dmp.start_velocity
        if start_velocity is None
        else _vector(start_velocity, "start_velocity", dims)
    )
    goal_vel = (
        dmp.goal_velocity
        if goal_velocity is None
        else _vector(goal_velocity, "goal_velocity", dims)
    )
    if dt is not None:
        if n_samples is not None:
            raise UsageError("n_samples, dt: give one of them, not both")
        n_samples = max(round(tau / _positive(dt, "dt")) + 1, 2)
    n = dmp.n_samples if n_samples is None else _count(n_samples, "n_samples", minimum=2)

    per_basis = _count(samples_per_basis, "samples_per_basis", minimum=1)
    every = max(1, math.ceil(per_basis * dmp.n_basis / (n - 1)))
    s = np.linspace(0.0, 1.0, (n - 1) * every + 1)  # integration grid, time in units of tau
    x = np.exp(-dmp.alpha_x * s)
    with _one_blas_thread():
        u = _forcing(x, dmp.centres, dmp.widths, dmp.weights)
        u += np.outer(1.0 - x, end - start)
        if goal_vel.any():  # the moving goal (prg.pipeline.dmp.model)
            u += np.outer(s - 1.0, tau * goal_vel) + dmp.damping * tau * goal_vel / dmp.stiffness
        e = _response(u, dmp.stiffness, dmp.damping, tau * start_vel)
    return e[::every] + start
