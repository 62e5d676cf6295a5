"""The discrete DMP: its formulation, and the fitted DMP as plain data (:class:`DMP`).

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

Accuracy (``tests/prg/pipeline/test_dmp.py``): with the defaults a 1000-point word-like curve 20 cm wide and
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

import dataclasses
from typing import Any

import numpy as np

from prg.errors import UsageError
from prg.pipeline.dmp.settings import _FloatArray
from prg.pipeline.dmp.validation import (
    _count,
    _finite,
    _nonnegative,
    _positive,
    _vector,
)


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
