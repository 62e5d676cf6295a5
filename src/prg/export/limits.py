"""Safe to send: a robot arm's joint trajectory checked against the arm's limits before export.

Both checks run on the **commanded** trajectory — the joint positions of every waypoint at its
time, what a robot's trajectory controller is sent — not on the simulated arm's response.

Joint limits (:func:`check_timing`)
    Positions must lie within ``[lower, upper]`` (the tighter of the URDF and the datasheet,
    :meth:`JointLimits.tighter`). Velocity, acceleration and jerk are divided differences of the
    positions at their own times (the spacing may vary, :func:`divided_differences`): a
    velocity over two consecutive waypoints, an acceleration over three, a jerk over four. Slowing the whole timing uniformly by ``k`` (every time
    multiplied by ``k``) divides velocities by ``k``, accelerations by ``k²`` and jerks by ``k³``,
    so the smallest ``k`` that fits is ``max(1, r_v, sqrt(r_a), cbrt(r_j))``, ``r`` the largest
    ratio of a value to its limit. A position out of its limits, or a ``k`` above
    :attr:`LimitSettings.max_slow_down`, is refused: slowing down does not help the first and
    the second would write too slowly to be what was planned.

Pen contact (:func:`check_contact`)
    The simulator's pen has no collision geometry: its tip inks while within the contact band
    ``+-control.contact_band_mm`` of the paper surface (:func:`prg.sim.geometry.in_contact`), so
    the band's lower half is how far the pen may press into the paper (its compliance) and its
    upper half how far above it the pen still inks. Every pen-down waypoint must be at most
    ``contact_above_mm`` above the surface, and no waypoint (pen down or up) more than
    ``compliance_mm`` below it.

Everything here is a pure function of arrays; :mod:`prg.export.robot` feeds it the waypoints.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prg.errors import SettingsError, UsageError
from prg.export.settings import LimitSettings
from prg.fields import check

__all__ = [
    "QUANTITIES",
    "ContactCheck",
    "JointLimits",
    "LimitSettings",
    "TimingCheck",
    "check_contact",
    "check_timing",
    "divided_differences",
]

QUANTITIES = ("velocity", "acceleration", "jerk")
_POWER = {"velocity": 1, "acceleration": 2, "jerk": 3}  # a uniform slow-down k divides by k**power
_UNITS = {"velocity": "rad/s", "acceleration": "rad/s²", "jerk": "rad/s³"}
_SLACK = 1e-9  # relative: a value this close to its limit fits (the slowed timing's own rounding)


def _limit_vector(value: Any, name: str, n: int, *, positive: bool) -> NDArray[np.float64] | None:
    if value is None:
        return None
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise SettingsError(name, f"must be {n} numbers, got {value!r}") from None
    check(arr.shape == (n,), name, f"must be {n} numbers (one per joint), got {value!r}")
    if positive:
        ok = bool(np.all(np.isfinite(arr) & (arr > 0)))
        check(ok, name, f"must be positive finite numbers, got {value!r}")
    else:  # a position limit may be unbounded (a joint without one in the datasheet)
        check(not np.any(np.isnan(arr)), name, f"must be numbers, got {value!r}")
    return arr


@dataclass(frozen=True)
class JointLimits:
    """Per-joint limits of an arm, in the order of ``names``; a quantity without limits is None.

    Attributes
    ----------
    names : tuple of str
    lower, upper : ndarray, shape (J,)
        Position limits (rad).
    velocity, acceleration, jerk : ndarray, shape (J,), or None
        Largest magnitudes (rad/s, rad/s², rad/s³).
    source : str
        Where the numbers come from (the URDF, a datasheet, both).
    """

    names: tuple[str, ...]
    lower: NDArray[np.float64]
    upper: NDArray[np.float64]
    velocity: NDArray[np.float64] | None = None
    acceleration: NDArray[np.float64] | None = None
    jerk: NDArray[np.float64] | None = None
    source: str = ""

    def __post_init__(self) -> None:
        names = tuple(str(n) for n in self.names)
        check(len(names) > 0, "names", "must name at least one joint")
        n = len(names)
        object.__setattr__(self, "names", names)
        for name in ("lower", "upper"):
            object.__setattr__(
                self, name, _limit_vector(getattr(self, name), name, n, positive=False)
            )
        for name in QUANTITIES:
            object.__setattr__(
                self, name, _limit_vector(getattr(self, name), name, n, positive=True)
            )
        check(bool(np.all(self.lower < self.upper)), "lower", "must be below upper for every joint")

    @classmethod
    def from_mapping(cls, names: Sequence[str], node: Mapping[str, Any]) -> JointLimits:
        """From a datasheet node (``conf/export.yaml``'s ``limits.joints.<robot>``): ``source``,
        ``lower``, ``upper``, ``velocity``, ``acceleration``, ``jerk`` (each optional but
        ``source``; a missing position limit is unbounded).

        Raises
        ------
        SettingsError
            Naming the field (the caller adds the node's path).
        """
        check(isinstance(node, Mapping), "limits", f"must be a mapping, got {node!r}")
        known = ("source", "lower", "upper", *QUANTITIES)
        for key in node:
            check(key in known, str(key), f"is not a joint limit: accepted are {', '.join(known)}")
        check("source" in node, "source", "is missing: say where the numbers come from")
        n = len(names)
        return cls(
            names=tuple(names),
            lower=np.full(n, -np.inf) if node.get("lower") is None else node["lower"],
            upper=np.full(n, np.inf) if node.get("upper") is None else node["upper"],
            velocity=node.get("velocity"),
            acceleration=node.get("acceleration"),
            jerk=node.get("jerk"),
            source=str(node["source"]),
        )

    def tighter(self, other: JointLimits | None) -> JointLimits:
        """Per joint and quantity, the stricter of ``self`` and ``other`` (same joints)."""
        if other is None:
            return self
        if other.names != self.names:
            raise UsageError(
                f"joint limits for {', '.join(other.names)} do not match the arm's joints "
                f"{', '.join(self.names)}"
            )

        def both(a, b, pick):
            if a is None or b is None:
                return b if a is None else a
            return pick(a, b)

        return JointLimits(
            names=self.names,
            lower=np.maximum(self.lower, other.lower),
            upper=np.minimum(self.upper, other.upper),
            velocity=both(self.velocity, other.velocity, np.minimum),
            acceleration=both(self.acceleration, other.acceleration, np.minimum),
            jerk=both(self.jerk, other.jerk, np.minimum),
            source="; ".join(s for s in (self.source, other.source) if s),
        )

    def of(self, quantity: str) -> NDArray[np.float64] | None:
        return getattr(self, quantity)


# ----------------------------------------------------------------------------- the timing


def divided_differences(
    t: ArrayLike, q: ArrayLike
) -> dict[str, tuple[NDArray[np.float64], NDArray[np.float64]]]:
    """Velocity, acceleration and jerk of a trajectory by divided differences, and their times.

    The k-th derivative over ``k + 1`` consecutive samples is ``k!`` times their Newton divided
    difference, exact for a polynomial of degree ``k`` whatever the spacing (a velocity between
    two samples, an acceleration over three, a jerk over four); it is given at the mean time of
    its samples (where it is exact for a polynomial of degree ``k + 1``).

    Parameters
    ----------
    t : array_like, shape (n,)
        Strictly increasing times (s), any spacing.
    q : array_like, shape (n, J)
        Joint positions.

    Returns
    -------
    dict
        ``quantity -> (values, times)``: ``velocity`` shape (n - 1, J), ``acceleration``
        (n - 2, J), ``jerk`` (n - 3, J).
    """
    times = np.asarray(t, dtype=np.float64)
    values = np.asarray(q, dtype=np.float64)
    out = {}
    for k, quantity in enumerate(QUANTITIES, start=1):
        span = times[k:] - times[:-k]
        values = k * np.diff(values, axis=0) / span[:, None]
        at = np.mean([times[i : len(times) - k + i] for i in range(k + 1)], axis=0)
        out[quantity] = (values, at)
    return out


@dataclass(frozen=True)
class TimingCheck:
    """The joint-limit check of a timing.

    Attributes
    ----------
    slow_down : float
        The uniform slow-down applied (1: the timing fits as planned).
    ratios : dict
        Per quantity (``velocity``, ``acceleration``, ``jerk`` with limits), the largest
        ``|value| / limit`` of the timing **as planned** (after the slow-down: divided by
        ``slow_down ** power``).
    worst : dict
        Per quantity, ``(joint name, time in s)`` of that largest ratio (planned timing).
    position_margin_rad : float
        The smallest distance of any joint to its position limits.
    """

    slow_down: float
    ratios: dict[str, float] = field(default_factory=dict)
    worst: dict[str, tuple[str, float]] = field(default_factory=dict)
    position_margin_rad: float = math.inf

    @property
    def limiting(self) -> str | None:
        """The quantity that sets the slow-down (None when there is none)."""
        if self.slow_down <= 1.0:
            return None
        return max(self.ratios, key=lambda k: self.ratios[k] ** (1 / _POWER[k]))

    def describe(self) -> str:
        """One line: the slow-down and what set it, or the largest ratio when none."""
        if not self.ratios:
            return "no velocity, acceleration or jerk limits to check"
        key = self.limiting or max(self.ratios, key=lambda k: self.ratios[k] ** (1 / _POWER[k]))
        joint, when = self.worst[key]
        what = f"the {key} of {joint} at t = {when:.2f} s is {self.ratios[key]:.3g}x its limit"
        if self.slow_down > 1.0:
            return f"timing slowed {self.slow_down:.4g}x: {what} as planned"
        return f"fits as planned: {what}"

    def as_dict(self) -> dict[str, Any]:
        return {
            "slow_down": self.slow_down,
            "limiting": self.limiting,
            "ratios_as_planned": dict(self.ratios),
            "ratios_as_sent": {k: r / self.slow_down ** _POWER[k] for k, r in self.ratios.items()},
            "worst": {k: {"joint": j, "t_s": w} for k, (j, w) in self.worst.items()},
            "position_margin_rad": self.position_margin_rad,
        }


def _check_positions(t: NDArray, q: NDArray, limits: JointLimits) -> float:
    below = limits.lower - q
    above = q - limits.upper
    excess = np.maximum(below, above)
    i, j = np.unravel_index(int(np.argmax(excess)), excess.shape)
    if excess[i, j] > 0:
        raise UsageError(
            f"{limits.names[j]} reaches {q[i, j]:.4f} rad at t = {t[i]:.2f} s, outside its limits "
            f"[{limits.lower[j]:.4f}, {limits.upper[j]:.4f}] rad ({limits.source}): nothing is "
            "exported; place the word elsewhere (paper.word_centre_cm) or smaller (scale)"
        )
    return float(-excess.max())


def check_timing(
    t: ArrayLike, q: ArrayLike, limits: JointLimits, max_slow_down: float = math.inf
) -> TimingCheck:
    """Check a joint trajectory against ``limits``; the smallest uniform slow-down that fits.

    Parameters
    ----------
    t : array_like, shape (n,)
        Strictly increasing times (s).
    q : array_like, shape (n, J)
        Joint positions (rad), columns in the order of ``limits.names``.
    limits : JointLimits
    max_slow_down : float
        The largest slow-down accepted.

    Returns
    -------
    TimingCheck
        Multiply ``t`` by its ``slow_down`` to send a timing within every limit.

    Raises
    ------
    UsageError
        One line: a position outside its limits (naming the joint, value, limits and time), or a
        slow-down beyond ``max_slow_down`` (naming what needs it).
    """
    times = np.asarray(t, dtype=np.float64)
    pos = np.asarray(q, dtype=np.float64)
    if times.ndim != 1 or pos.shape != (len(times), len(limits.names)) or len(times) < 2:
        raise UsageError(
            f"a trajectory of {len(limits.names)} joints must have shape (n >= 2, "
            f"{len(limits.names)}) with n times, got {pos.shape} and {times.shape}"
        )
    if not np.all(np.diff(times) > 0):
        raise UsageError("the trajectory's times must be strictly increasing")
    margin = _check_positions(times, pos, limits)
    ratios: dict[str, float] = {}
    worst: dict[str, tuple[str, float]] = {}
    for quantity, (values, at) in divided_differences(times, pos).items():
        bound = limits.of(quantity)
        if bound is None or not len(values):
            continue
        ratio = np.abs(values) / bound
        i, j = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
        ratios[quantity] = float(ratio[i, j])
        worst[quantity] = (limits.names[j], float(at[i]))
    needed = max([1.0, *(r ** (1 / _POWER[k]) for k, r in ratios.items())])
    result = TimingCheck(needed, ratios, worst, margin)
    if needed > max_slow_down * (1 + _SLACK):
        key = result.limiting
        joint, when = worst[key]
        raise UsageError(
            f"the {key} of {joint} at t = {when:.2f} s is {ratios[key]:.3g}x its limit "
            f"({limits.of(key)[limits.names.index(joint)]:g} {_UNITS[key]}, {limits.source}): the "
            f"timing must be slowed {needed:.3g}x, more than limits.max_slow_down={max_slow_down:g}; "
            "write slower (a larger tempo) or allow more slow-down"
        )
    return result


# ----------------------------------------------------------------------------- the pen


@dataclass(frozen=True)
class ContactCheck:
    """The pen-contact check of a trajectory (heights in mm above the paper surface).

    Attributes
    ----------
    above_mm : float
        The highest pen-down waypoint above the paper (negative: all pressed into it).
    below_mm : float
        The deepest any waypoint goes below the paper surface (0 when none does).
    above_limit_mm, compliance_mm : float
        What was allowed.
    """

    above_mm: float
    below_mm: float
    above_limit_mm: float
    compliance_mm: float

    def as_dict(self) -> dict[str, float]:
        return {
            "pen_down_highest_mm": self.above_mm,
            "deepest_below_paper_mm": self.below_mm,
            "allowed_above_mm": self.above_limit_mm,
            "compliance_mm": self.compliance_mm,
        }


def check_contact(
    heights_mm: ArrayLike,
    pen_down: ArrayLike,
    t: ArrayLike,
    above_mm: float,
    compliance_mm: float,
) -> ContactCheck:
    """Check the pen's height over the paper at every waypoint.

    Parameters
    ----------
    heights_mm : array_like, shape (n,)
        The pen tip's height above the paper surface (mm; negative: pressed into it).
    pen_down : array_like of bool, shape (n,)
        The waypoints that should ink.
    t : array_like, shape (n,)
        Their times (s), to name a culprit.
    above_mm, compliance_mm : float
        Allowed height of a pen-down waypoint above the paper, and depth of any below it.

    Returns
    -------
    ContactCheck

    Raises
    ------
    UsageError
        A pen-down waypoint too high to ink, or a waypoint pressed too deep.
    """
    h = np.asarray(heights_mm, dtype=np.float64)
    down = np.asarray(pen_down, dtype=bool)
    times = np.asarray(t, dtype=np.float64)
    if not down.any():
        raise UsageError("the trajectory has no pen-down waypoint: nothing would be written")
    i = int(np.argmax(np.where(down, h, -np.inf)))
    if h[i] > above_mm:
        raise UsageError(
            f"the pen is {h[i]:.3f} mm above the paper at t = {times[i]:.2f} s while it should "
            f"write (at most {above_mm:g} mm inks): nothing is exported"
        )
    k = int(np.argmin(h))
    if -h[k] > compliance_mm:
        raise UsageError(
            f"the pen presses {-h[k]:.3f} mm into the paper at t = {times[k]:.2f} s, more than "
            f"the {compliance_mm:g} mm it gives: nothing is exported"
        )
    return ContactCheck(float(h[i]), float(max(0.0, -h[k])), float(above_mm), float(compliance_mm))
