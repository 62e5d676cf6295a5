"""Argument checks of the DMP's public functions: each names the argument that is out of range.

Every check raises :class:`prg.errors.UsageError` (a ``ValueError``) and returns the value in the
type the numeric code uses (float64 arrays, floats, ints).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from prg.errors import UsageError
from prg.pipeline.dmp.settings import VELOCITIES, _FloatArray


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


def _velocities(value: Any) -> bool:
    """Whether ``velocities`` asks for the demonstrated ones (else at rest)."""
    if value not in VELOCITIES:
        raise UsageError(f"velocities: expected one of {', '.join(VELOCITIES)}, got {value!r}")
    return value == "demonstrated"
