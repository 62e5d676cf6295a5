"""Discrete Dynamic Movement Primitives (DMPs) for whole handwritten words, in NumPy.

A DMP (Ijspeert, Nakanishi, Hoffmann, Pastor, Schaal 2013, "Dynamical movement primitives:
learning attractor models for motor behaviors", Neural Computation 25(2)) encodes a demonstrated
trajectory ``y(t)`` (here a 2-D word in centimetres, one DMP per word) as a stable spring-damper
pulled towards the goal ``g``, plus a learned forcing term that fades out with a phase ``x``.

**Formulation** (per dimension, ``v = tau y'``)::

    tau x' = -alpha_x x,                       x(0) = 1   =>  x(t) = exp(-alpha_x t / tau)
    tau v' = K (g_m(t) - y) + D (tau g' - v) - K (g - y0) x + K f(x),  y(0) = y0, v(0) = tau y0'
    g_m(t) = g - g' (tau - t)                  (the goal, moving at the goal velocity g')
    f(x)   = x * sum_i psi_i(x) w_i / sum_i psi_i(x),     psi_i(x) = exp(-h_i (x - c_i)^2)

With the start velocity ``y0'`` and the goal velocity ``g'`` both zero (the default, and what the
word pipeline uses: a pen starts and stops at rest) this is the rest-to-rest DMP below. A
demonstration that is already moving at its first sample, or still moving at its last (a person's
pen, the LASA shapes), is followed from its demonstrated start velocity (the initial state, as in
Ijspeert et al. 2013 and ``movement_primitives``' ``start_yd``) towards a goal that moves at its
demonstrated final velocity and arrives at ``g`` at ``t = tau`` (the moving-goal form of Kober,
Mülling, Krömer, Lampert, Schölkopf, Peters 2010, "Movement templates for learning of hitting and
batting", ICRA, and Mülling, Kober, Kroemer, Peters 2013, IJRR 32(3)): ``fit_dmp(...,
velocities="demonstrated")``.

This is the modification of Hoffmann, Pastor, Park, Schaal (2009, ICRA, "Biologically-inspired
dynamical systems for movement generation") and Pastor, Hoffmann, Asfour, Schaal (2009, ICRA,
"Learning and generalization of motor skills by learning from demonstration"), not the 2013
paper's form ``tau z' = alpha_z (beta_z (g - y) - z) + f`` whose ``f`` is multiplied by
``(g - y0)``. The reason is words: a word starts and ends at about the same height, so ``g - y0``
is close to zero in ``y`` (and its sign is arbitrary); the ``(g - y0)``-scaled form then needs
huge weights for the vertical strokes and flips or blows the word up when the goal moves a little.
Here the forcing term is not scaled, and the system is linear in ``(y0, g, f)``: a new start or
goal only adds the smooth, shape-free transition ``(g_new - g) s(t)`` (or ``(y0_new - y0)(1 -
s(t))``) to the demonstrated path, where ``s`` is the zero-weight DMP from 0 to 1; it rises
monotonically and reaches about 0.975 at ``t = tau`` with the defaults (``x(tau) = 0.01``), so a
moved goal is met within 2.5 % of the move at ``t = tau`` and exactly as ``t -> inf``.
Defaults: ``K = 156.25``, ``D = 2 sqrt(K) = 25`` (critical damping; the paper's ``alpha_z = 25``,
``beta_z = alpha_z / 4``) and ``alpha_x = ln 100``.

**Basis functions** are spaced evenly in time: ``c_i = exp(-alpha_x i / (N - 1))``, and their
widths follow the local spacing, ``h_i = 1 / (2 (WIDTH_FACTOR (c_i - c_{i+1}))^2)`` (the last
reuses the previous spacing), so every Gaussian covers about the same span of time.

**Fitting** (:func:`fit_dmp`): the demonstration is taken on a uniform time grid over ``[0, tau]``
(``n`` points); velocities and accelerations come from five-point (fourth-order) finite differences
(one-sided near the ends). The target forcing values ``F = (tau^2 y'' + D tau y') / K - (g_m(t) -
y) + (g - y0) x - D tau g' / K`` (``y0`` the first point, ``g`` the last, ``g'`` zero or the last
point's velocity) are regressed on the design matrix
``Phi[k, i] = x_k psi_i(x_k) / sum_j psi_j(x_k)`` with **one** ridge solve for all basis functions
and all dimensions::

    W = argmin (1/n) ||Phi W - F||^2 + regularisation ||W||^2
      = solve(Phi^T Phi / n + regularisation I, Phi^T F / n)     (banded Cholesky; lstsq if 0)

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

Basis functions are local, so the design matrix is evaluated only within ``_BAND`` columns of
each sample's nearest centre (the columns left out are below ``1e-16`` of the largest; checked,
else the full matrix is used); :func:`design_matrix` is the plain dense definition.

Accuracy (``tests/test_dmp.py``): with the defaults a 1000-point word-like curve 20 cm wide and
4 cm tall that starts and ends at rest (twelve loops of varying height) is reproduced with an RMSE
of about 1e-4 mm; the fourth-order differences and the cubic hold matter (second-order differences
with a linear hold leave about 0.06 mm).

Fitted at rest (the default), the DMP starts at rest (``v(0) = 0``), as a pen does. A
demonstration that starts at speed ``v0`` is then followed with the transient error ``-v0 t
exp(-omega t)``, ``omega = sqrt(K) / tau``, largest (``v0 tau / (e sqrt(K))``) at ``t = tau /
sqrt(K)`` and below 5 % of that from ``t = tau / 2`` on: 0.6 cm for a straight 20 cm stroke at
constant speed, 1.4 cm for a loopy 20 cm word (100 cm of path) at constant speed. Such a
demonstration is fitted with ``velocities="demonstrated"``, which removes that transient exactly
(measured on the LASA set: ``benchmarks/bench_lasa.py``).
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import math
from collections.abc import Iterator
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from prg.errors import UsageError

__all__ = [
    "ALPHA_X",
    "BASIS_MAXIMUM",
    "BASIS_MINIMUM",
    "BASIS_PER_100_POINTS",
    "DAMPING",
    "DMP",
    "REGULARISATION",
    "SAMPLES_PER_BASIS",
    "STIFFNESS",
    "VELOCITIES",
    "WIDTH_FACTOR",
    "basis_count",
    "basis_functions",
    "design_matrix",
    "fit_dmp",
    "forcing_targets",
    "phase",
    "rollout",
    "uniform_in_time",
]

STIFFNESS = 156.25
"""Default spring constant ``K`` (``alpha_z beta_z`` with ``alpha_z = 25``, ``beta_z = 6.25``)."""
DAMPING = 2.0 * math.sqrt(STIFFNESS)
"""Default damping ``D``: critical, ``2 sqrt(K) = 25``."""
ALPHA_X = math.log(100.0)
"""Default canonical-system constant: the phase falls to 0.01 at ``t = tau``."""
WIDTH_FACTOR = 1.0
"""Standard deviation of each Gaussian in units of the spacing between neighbouring centres."""
VELOCITIES = ("rest", "demonstrated")
"""What :func:`fit_dmp` takes for the start and goal velocities (``velocities=``)."""
REGULARISATION = 1e-12
"""Default ridge parameter of :func:`fit_dmp` (on the per-sample mean squared error)."""
BASIS_PER_100_POINTS = 20.0
"""Default basis functions per 100 points of :func:`basis_count`."""
BASIS_MINIMUM = 20
"""Default lower bound of :func:`basis_count`."""
BASIS_MAXIMUM = 2000
"""Default upper bound of :func:`basis_count`."""
SAMPLES_PER_BASIS = 4
"""Least number of integration samples per basis function in :func:`rollout`."""

_BAND = 12  # columns of the design matrix kept either side of a sample's nearest centre
_NEGLIGIBLE = math.log(1e-16)  # log of the largest activation ratio that may be left out
_FD_POINTS = 5  # finite-difference stencil (fourth order)
_HOLD_POINTS = 4  # samples of the input interpolated on each rollout step (cubic)

_FloatArray = NDArray[np.float64]


@functools.cache
def _blas_controller() -> Any:
    """threadpoolctl's controller of the loaded BLAS libraries, or None without threadpoolctl."""
    try:
        from threadpoolctl import ThreadpoolController
    except ImportError:  # optional: without it BLAS keeps its default thread count
        return None
    return ThreadpoolController()


@contextlib.contextmanager
def _one_blas_thread() -> Iterator[None]:
    """Single-threaded BLAS/LAPACK for the small products and the banded Cholesky of a DMP.

    Threads gain nothing at these sizes, and OpenBLAS's threaded banded Cholesky stalls on a busy
    CPU (measured on a loaded 2-core machine, 300 basis functions: 2.2 s with 2 threads, 0.3 ms
    with one).
    """
    controller = _blas_controller()
    if controller is None:
        yield
        return
    with controller.limit(limits=1, user_api="blas"):
        yield


@dataclasses.dataclass(frozen=True, eq=False)
class DMP:
    """A fitted discrete DMP (formulation in the module docstring); plain, read-only data.

    Attributes
    ----------
    weights : ndarray, shape (n_basis, dims)
        Forcing-term weights ``w_i``, one column per dimension.
    y0 : ndarray, shape (dims,)
        Start of the demonstration.
    goal : ndarray, shape (dims,)
        End of the demonstration (the attractor ``g``).
    tau : float
        Duration of the demonstration (time constant of both systems), > 0.
    stiffness : float
        Spring constant ``K`` > 0.
    damping : float
        Damping ``D`` >= 0.
    alpha_x : float
        Canonical-system constant: ``x(t) = exp(-alpha_x t / tau)``.
    centres : ndarray, shape (n_basis,)
        Basis-function centres ``c_i`` in phase, strictly decreasing.
    widths : ndarray, shape (n_basis,)
        Basis-function widths ``h_i > 0`` in phase.
    n_samples : int
        Number of points of the demonstration: the default number of rollout samples.
    start_velocity : ndarray, shape (dims,)
        Velocity ``y0'`` at ``t = 0`` (per second; zeros: starts at rest).
    goal_velocity : ndarray, shape (dims,)
        Velocity ``g'`` of the moving goal, and so of the rollout at ``t = tau`` (per second;
        zeros: ends at rest).
    """

    weights: _FloatArray
    y0: _FloatArray
    goal: _FloatArray
    tau: float
    stiffness: float
    damping: float
    alpha_x: float
    centres: _FloatArray
    widths: _FloatArray
    n_samples: int
    start_velocity: _FloatArray | None = None
    goal_velocity: _FloatArray | None = None

    def __post_init__(self) -> None:
        for name in ("start_velocity", "goal_velocity"):
            if getattr(self, name) is None:
                object.__setattr__(self, name, np.zeros(np.shape(self.y0)))
        for name in ("weights", "y0", "goal", "centres", "widths", *_VELOCITIES):
            arr = np.array(getattr(self, name), dtype=np.float64)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    @property
    def n_basis(self) -> int:
        """Number of basis functions ``N``."""
        return int(self.weights.shape[0])

    @property
    def dims(self) -> int:
        """Number of dimensions of the trajectory."""
        return int(self.weights.shape[1])

    def to_dict(self) -> dict[str, Any]:
        """JSON-able plain data (lists, floats, ints); :meth:`from_dict` restores it exactly."""
        return {
            "n_basis": self.n_basis,
            "weights": self.weights.tolist(),
            "y0": self.y0.tolist(),
            "goal": self.goal.tolist(),
            "tau": float(self.tau),
            "stiffness": float(self.stiffness),
            "damping": float(self.damping),
            "alpha_x": float(self.alpha_x),
            "centres": self.centres.tolist(),
            "widths": self.widths.tolist(),
            "n_samples": int(self.n_samples),
            "start_velocity": self.start_velocity.tolist(),
            "goal_velocity": self.goal_velocity.tolist(),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> DMP:
        """The DMP stored by :meth:`to_dict`, validated (shapes agree, values finite, in range).

        The two velocities may be absent (a DMP stored before they existed): zeros, at rest."""
        missing = sorted(_FIELDS - set(_VELOCITIES) - set(data))
        if missing:
            raise UsageError(f"DMP data: missing keys {missing}")
        weights = _finite(data["weights"], "weights", ndim=2)
        n_basis, dims = weights.shape
        if n_basis < 1 or dims < 1:
            raise UsageError(
                f"weights: expected shape (n_basis >= 1, dims >= 1), got {weights.shape}"
            )
        if "n_basis" in data and data["n_basis"] != n_basis:
            raise UsageError(f"n_basis: {data['n_basis']!r} does not match {n_basis} weight rows")
        centres = _vector(data["centres"], "centres", n_basis)
        if np.any(np.diff(centres) >= 0):
            raise UsageError("centres: expected strictly decreasing values")
        widths = _vector(data["widths"], "widths", n_basis)
        if np.any(widths <= 0):
            raise UsageError("widths: expected values > 0")
        return cls(
            weights=weights,
            y0=_vector(data["y0"], "y0", dims),
            goal=_vector(data["goal"], "goal", dims),
            tau=_positive(data["tau"], "tau"),
            stiffness=_positive(data["stiffness"], "stiffness"),
            damping=_nonnegative(data["damping"], "damping"),
            alpha_x=_positive(data["alpha_x"], "alpha_x"),
            centres=centres,
            widths=widths,
            n_samples=_count(data["n_samples"], "n_samples", minimum=2),
            **{
                name: _vector(data[name], name, dims)
                for name in _VELOCITIES
                if data.get(name) is not None
            },
        )


_VELOCITIES = ("start_velocity", "goal_velocity")
_FIELDS = frozenset(field.name for field in dataclasses.fields(DMP))


# ----------------------------------------------------------------------------- validation


def _finite(value: ArrayLike, name: str, ndim: int) -> _FloatArray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise UsageError(
            f"{name}: expected an array of numbers, got {type(value).__name__}"
        ) from None
    if arr.ndim != ndim:
        raise UsageError(f"{name}: expected a {ndim}-D array, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise UsageError(f"{name}: expected finite values, got NaN or inf")
    return arr


def _vector(value: ArrayLike, name: str, size: int) -> _FloatArray:
    arr = _finite(value, name, ndim=1)
    if arr.shape != (size,):
        raise UsageError(f"{name}: expected shape ({size},), got shape {arr.shape}")
    return arr


def _real(value: Any, name: str) -> float:
    if isinstance(value, bool):
        raise UsageError(f"{name}: expected a number, got {value!r}")
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise UsageError(f"{name}: expected a number, got {value!r}") from None
    if not math.isfinite(out):
        raise UsageError(f"{name}: expected a finite number, got {out}")
    return out


def _positive(value: Any, name: str) -> float:
    out = _real(value, name)
    if out <= 0:
        raise UsageError(f"{name}: expected a number > 0, got {out}")
    return out


def _nonnegative(value: Any, name: str) -> float:
    out = _real(value, name)
    if out < 0:
        raise UsageError(f"{name}: expected a number >= 0, got {out}")
    return out


def _count(value: Any, name: str, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise UsageError(f"{name}: expected an integer >= {minimum}, got {value!r}")
    if value < minimum:
        raise UsageError(f"{name}: expected an integer >= {minimum}, got {value}")
    return int(value)


def _points(points: ArrayLike) -> _FloatArray:
    arr = _finite(points, "points", ndim=2)
    if arr.shape[0] < 3 or arr.shape[1] < 1:
        raise UsageError(
            f"points: expected shape (n, dims) with n >= 3 points and dims >= 1, got {arr.shape}"
        )
    return arr


# ----------------------------------------------------------------------------- building blocks


def basis_count(
    n_points: int,
    per_100_points: float = BASIS_PER_100_POINTS,
    minimum: int = BASIS_MINIMUM,
    maximum: int = BASIS_MAXIMUM,
) -> int:
    """Number of basis functions for a trajectory of ``n_points`` points.

    ``round(n_points * per_100_points / 100)`` clipped to ``[minimum, maximum]``. A word's point
    count grows with its length (about 100 points a letter), and so does the detail the forcing
    term must carry. The defaults (20 per 100 points, at least 20, at most 2000) give 200 basis
    functions for a 1000-point word; a 1000-point curve of twelve loops then reproduces to about
    1e-4 mm, and 100 (about eight per loop) still to about 2e-4 mm, while 75 leave 0.03 mm and 50
    leave 1.4 mm: the defaults keep a margin of about two for words with denser strokes.

    Parameters
    ----------
    n_points : int
        Number of points of the trajectory, >= 1.
    per_100_points : float
        Basis functions per 100 points, > 0.
    minimum, maximum : int
        Bounds on the result, ``1 <= minimum <= maximum``.

    Returns
    -------
    int
    """
    n_points = _count(n_points, "n_points", minimum=1)
    per_100_points = _positive(per_100_points, "per_100_points")
    minimum = _count(minimum, "minimum", minimum=1)
    maximum = _count(maximum, "maximum", minimum=minimum)
    return int(min(max(round(n_points * per_100_points / 100.0), minimum), maximum))


def phase(t: ArrayLike, tau: float, alpha_x: float = ALPHA_X) -> _FloatArray:
    """Closed-form phase of the canonical system, ``x(t) = exp(-alpha_x t / tau)``.

    Parameters
    ----------
    t : array_like, shape (n,)
        Times.
    tau : float
        Time constant (duration), > 0.
    alpha_x : float
        Decay constant, > 0.

    Returns
    -------
    ndarray, shape (n,)
    """
    return np.exp(-alpha_x * np.asarray(t, dtype=np.float64) / tau)


def basis_functions(
    n_basis: int, alpha_x: float = ALPHA_X, width_factor: float = WIDTH_FACTOR
) -> tuple[_FloatArray, _FloatArray]:
    """Centres and widths of ``n_basis`` Gaussians in phase, spaced evenly in time.

    Parameters
    ----------
    n_basis : int
        Number of basis functions, >= 1.
    alpha_x : float
        Canonical-system constant, > 0.
    width_factor : float
        Standard deviation of each Gaussian in units of the spacing to the next centre, > 0.

    Returns
    -------
    centres : ndarray, shape (n_basis,)
        ``exp(-alpha_x * linspace(0, 1, n_basis))``, decreasing (``[1.0]`` for one).
    widths : ndarray, shape (n_basis,)
        ``h_i = 1 / (2 (width_factor (c_i - c_{i+1}))^2)``; the last reuses the previous spacing;
        a single basis function gets the spacing ``1 - exp(-alpha_x)``.
    """
    n_basis = _count(n_basis, "n_basis", minimum=1)
    alpha_x = _positive(alpha_x, "alpha_x")
    width_factor = _positive(width_factor, "width_factor")
    if n_basis == 1:
        centres = np.ones(1)
        spacing = np.array([1.0 - math.exp(-alpha_x)])
    else:
        centres = np.exp(-alpha_x * np.linspace(0.0, 1.0, n_basis))
        spacing = -np.diff(centres)
        spacing = np.append(spacing, spacing[-1])
    widths = 1.0 / (2.0 * (width_factor * spacing) ** 2)
    return centres, widths


def design_matrix(x: ArrayLike, centres: ArrayLike, widths: ArrayLike) -> _FloatArray:
    """Normalised, phase-gated basis activations ``x psi_i(x) / sum_j psi_j(x)`` (dense).

    Parameters
    ----------
    x : array_like, shape (n,)
        Phase values.
    centres, widths : array_like, shape (n_basis,)
        As from :func:`basis_functions`.

    Returns
    -------
    ndarray, shape (n, n_basis)
        ``f(x) = design_matrix(x, centres, widths) @ weights``. Rows are normalised in log space,
        so they stay finite where every Gaussian underflows.
    """
    x = np.asarray(x, dtype=np.float64)
    centres = np.asarray(centres, dtype=np.float64)
    widths = np.asarray(widths, dtype=np.float64)
    return _normalised(x, x[:, None] - centres, widths)


def _normalised(x: _FloatArray, offsets: _FloatArray, widths: _FloatArray) -> _FloatArray:
    """``x psi / sum(psi)`` row by row from ``offsets = x - c`` (n, m) and the matching widths.

    Works in place on ``offsets``, which becomes the result.
    """
    offsets *= offsets
    offsets *= -widths  # log psi
    offsets -= offsets.max(axis=1, keepdims=True)
    psi = np.exp(offsets, out=offsets)
    psi *= (x / psi.sum(axis=1))[:, None]
    return psi


def _design_band(
    x: _FloatArray, centres: _FloatArray, widths: _FloatArray
) -> tuple[_FloatArray, _FloatArray]:
    """:func:`design_matrix` near each sample's largest activation: ``(start, values)``.

    ``values[k, j]`` is column ``start[k] + j`` of row ``k``; the columns left out are below
    ``1e-16`` of the row's largest (checked on the two just outside the band, else all columns
    are kept: ``start = 0``, ``values`` dense). Shapes (n,) and (n, width).
    """
    n, n_basis = x.size, centres.size
    width = 2 * _BAND + 1
    if n_basis > width:
        # the largest activation is at one of the two centres around x (centres decrease)
        above = np.clip(n_basis - np.searchsorted(centres[::-1], x), 1, n_basis - 1)
        log_left = -widths[above - 1] * (x - centres[above - 1]) ** 2
        log_right = -widths[above] * (x - centres[above]) ** 2
        peak = np.where(log_left >= log_right, above - 1, above)
        start = np.clip(peak - _BAND, 0, n_basis - width)
        top = np.maximum(log_left, log_right)
        before = np.maximum(start - 1, 0)
        after = np.minimum(start + width, n_basis - 1)
        negligible = (
            (start == 0) | (-widths[before] * (x - centres[before]) ** 2 - top < _NEGLIGIBLE)
        ) & (
            (start + width == n_basis)
            | (-widths[after] * (x - centres[after]) ** 2 - top < _NEGLIGIBLE)
        )
        if negligible.all():
            cols = start[:, None] + np.arange(width)
            return start, _normalised(x, x[:, None] - centres[cols], widths[cols])
    return np.zeros(n, dtype=np.intp), design_matrix(x, centres, widths)


def _forcing(
    x: _FloatArray, centres: _FloatArray, widths: _FloatArray, weights: _FloatArray
) -> _FloatArray:
    """``f(x) = design_matrix(x, centres, widths) @ weights`` through the band, shape (n, dims)."""
    start, values = _design_band(x, centres, widths)
    if values.shape[1] == centres.size:
        return values @ weights
    cols = start[:, None] + np.arange(values.shape[1])
    return np.column_stack([np.einsum("kj,kj->k", values, w[cols]) for w in weights.T])


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


def _velocities(value: Any) -> bool:
    """Whether ``velocities`` asks for the demonstrated ones (else at rest)."""
    if value not in VELOCITIES:
        raise UsageError(f"velocities: expected one of {', '.join(VELOCITIES)}, got {value!r}")
    return value == "demonstrated"


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


# ----------------------------------------------------------------------------- fit and rollout


def uniform_in_time(
    points: ArrayLike, times: ArrayLike, n_samples: int | None = None
) -> tuple[_FloatArray, float]:
    """A demonstration sampled at irregular ``times`` (a pen on a tablet or a browser canvas),
    resampled uniformly in time for :func:`fit_dmp`.

    Samples that share a time are averaged into one (a browser can deliver two pointer events in
    the same millisecond), then a cubic spline through the rest (``scipy.interpolate``,
    not-a-knot ends, which leave the end velocities free) is evaluated at ``n_samples`` points
    evenly spaced from the first time to the last. The spline keeps the velocities and
    accelerations that the forcing targets are made of; linear interpolation would put a corner
    at every original sample.

    Parameters
    ----------
    points : array_like, shape (n, dims)
        Positions, finite.
    times : array_like, shape (n,)
        Their times, finite and non-decreasing, spanning more than zero.
    n_samples : int, optional
        Number of uniform samples, >= 3; default ``n``.

    Returns
    -------
    uniform : ndarray, shape (n_samples, dims)
        The positions at the uniform times; the first and last equal the first and last
        (time-averaged) samples.
    duration : float
        ``times[-1] - times[0]``: the ``tau`` to fit them with.
    """
    from scipy.interpolate import CubicSpline  # only here: scipy.interpolate costs an import

    y = _points(points)
    t = _finite(times, "times", ndim=1)
    if t.shape != (y.shape[0],):
        raise UsageError(f"times: expected shape ({y.shape[0]},) like points, got {t.shape}")
    if np.any(np.diff(t) < 0):
        raise UsageError("times: expected non-decreasing values")
    n = y.shape[0] if n_samples is None else _count(n_samples, "n_samples", minimum=3)
    unique, first = np.unique(t, return_index=True)
    if unique.size < 3:
        raise UsageError(f"times: expected at least 3 distinct times, got {unique.size}")
    counts = np.diff(np.append(first, t.size))
    merged = np.add.reduceat(y, first, axis=0) / counts[:, None]
    grid = np.linspace(unique[0], unique[-1], n)
    uniform = CubicSpline(unique, merged)(grid)
    uniform[0], uniform[-1] = merged[0], merged[-1]
    return uniform, float(unique[-1] - unique[0])


def fit_dmp(
    points: ArrayLike,
    tau: float = 1.0,
    n_basis: int | None = None,
    regularisation: float = REGULARISATION,
    *,
    stiffness: float = STIFFNESS,
    damping: float | None = None,
    alpha_x: float = ALPHA_X,
    width_factor: float = WIDTH_FACTOR,
    velocities: str = "rest",
) -> DMP:
    """Fit a DMP to one demonstration with a single ridge-regression solve.

    Parameters
    ----------
    points : array_like, shape (n, dims)
        The demonstration (e.g. a word in centimetres, ``dims = 2``) sampled uniformly in time,
        ``n >= 3`` finite points.
    tau : float
        Its duration, > 0.
    n_basis : int, optional
        Number of basis functions, >= 1; default ``basis_count(n)``.
    regularisation : float
        Ridge parameter ``lambda >= 0`` on the per-sample mean squared error (module docstring);
        0 gives the minimum-norm least-squares solution.
    stiffness : float
        ``K > 0``.
    damping : float, optional
        ``D >= 0``; default ``2 sqrt(K)`` (critical damping).
    alpha_x : float
        Canonical-system constant, > 0.
    width_factor : float
        Basis width in units of the centre spacing, > 0 (:func:`basis_functions`).
    velocities : {"rest", "demonstrated"}
        ``"rest"``: the DMP starts and ends at rest, whatever the demonstration does (a word's
        pen; the default). ``"demonstrated"``: it starts with the demonstration's first
        velocity and ends with its last (finite differences, as for the forcing targets), for
        demonstrations that are already moving at either end (module docstring).

    Returns
    -------
    DMP
        With ``y0 = points[0]``, ``goal = points[-1]``, ``n_samples = n`` and the two velocities.

    Raises
    ------
    ValueError
        (:class:`prg.errors.UsageError`) naming the argument that is out of range.
    """
    y = _points(points)
    n = y.shape[0]
    tau = _positive(tau, "tau")
    n_basis = basis_count(n) if n_basis is None else _count(n_basis, "n_basis", minimum=1)
    regularisation = _nonnegative(regularisation, "regularisation")
    stiffness = _positive(stiffness, "stiffness")
    damping = 2.0 * math.sqrt(stiffness) if damping is None else _nonnegative(damping, "damping")
    alpha_x = _positive(alpha_x, "alpha_x")
    demonstrated = _velocities(velocities)
    centres, widths = basis_functions(n_basis, alpha_x, width_factor)

    x, targets, start_velocity, goal_velocity = _targets(
        y, tau, stiffness, damping, alpha_x, demonstrated
    )
    start, values = _design_band(x, centres, widths)
    with _one_blas_thread():
        weights = _ridge(start, values, targets, regularisation, n_basis)
    return DMP(
        weights=weights,
        y0=y[0],
        goal=y[-1],
        tau=tau,
        stiffness=stiffness,
        damping=damping,
        alpha_x=alpha_x,
        centres=centres,
        widths=widths,
        n_samples=n,
        start_velocity=start_velocity,
        goal_velocity=goal_velocity,
    )


def _ridge(
    start: _FloatArray,
    values: _FloatArray,
    targets: _FloatArray,
    regularisation: float,
    n_basis: int,
) -> _FloatArray:
    """``argmin (1/n) ||Phi W - targets||^2 + regularisation ||W||^2``, one solve for all dims.

    ``Phi`` is given as a band (:func:`_design_band`); its Gram matrix is banded too (bandwidth
    ``width - 1``) and is built and factorised (Cholesky) in band storage.
    """
    n, width = values.shape
    phi = _dense(start, values, n_basis)
    if regularisation == 0:
        return np.linalg.lstsq(phi, targets, rcond=None)[0]
    banded = _banded_gram(phi, start, width)
    banded /= n
    banded[-1] += regularisation
    try:
        return scipy.linalg.solveh_banded(banded, phi.T @ targets / n, check_finite=False)
    except np.linalg.LinAlgError:  # not numerically positive definite: the same problem by lstsq
        augmented = np.vstack([phi / math.sqrt(n), math.sqrt(regularisation) * np.eye(n_basis)])
        padded = np.vstack([targets / math.sqrt(n), np.zeros((n_basis, targets.shape[1]))])
        return np.linalg.lstsq(augmented, padded, rcond=None)[0]


def _banded_gram(phi: _FloatArray, start: _FloatArray, width: int) -> _FloatArray:
    """``phi.T @ phi`` in upper band storage, ``banded[width - 1 - d, i + d] = gram[i, i + d]``.

    Row ``k`` of ``phi`` (n, n_basis) is zero outside columns ``start[k] .. start[k] + width -
    1``, so the Gram matrix has bandwidth ``width - 1``; it is built ``width`` rows at a time
    from the samples that reach them (one BLAS product per block).
    """
    n_basis = phi.shape[1]
    end = start + width
    banded = np.zeros((width, n_basis))
    for lo in range(0, n_basis, width):
        hi, far = min(lo + width, n_basis), min(lo + 2 * width, n_basis)
        if width == n_basis:  # no band: one symmetric product
            block = phi.T @ phi
        else:
            rows = np.flatnonzero((end > lo) & (start < hi))
            if rows.size and rows[-1] - rows[0] + 1 == rows.size:  # contiguous: a view
                rows = slice(rows[0], rows[-1] + 1)
            block = phi[rows, lo:hi].T @ phi[rows, lo:far]  # gram[lo:hi, lo:far]
        i, d = _band_entries(hi - lo, width, far - lo)
        banded[width - 1 - d, lo + i + d] = block[i, i + d]
    return banded


@functools.lru_cache(maxsize=16)
def _band_entries(rows: int, width: int, columns: int) -> tuple[_FloatArray, _FloatArray]:
    """Row ``i`` and diagonal ``d`` of each entry ``(i, i + d)``, ``d < width``, of a ``rows`` x
    ``columns`` block of a band (the same for every full block of :func:`_banded_gram`)."""
    i, d = np.nonzero(np.add.outer(np.arange(rows), np.arange(width)) < columns)
    i.setflags(write=False)
    d.setflags(write=False)
    return i, d


def _dense(start: _FloatArray, values: _FloatArray, n_basis: int) -> _FloatArray:
    """The full (n, n_basis) design matrix from its band."""
    n, width = values.shape
    if width == n_basis:
        return values
    out = np.zeros((n, n_basis))
    flat = (np.arange(n) * n_basis + start)[:, None] + np.arange(width)
    out.ravel()[flat.ravel()] = values.ravel()
    return out


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
        if goal_vel.any():  # the moving goal (module docstring)
            u += np.outer(s - 1.0, tau * goal_vel) + dmp.damping * tau * goal_vel / dmp.stiffness
        e = _response(u, dmp.stiffness, dmp.damping, tau * start_vel)
    return e[::every] + start
