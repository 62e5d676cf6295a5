"""Checked fields of the library's settings classes; each refusal is a
:class:`~prg.errors.SettingsError` naming the field alone.

A settings dataclass checks its own values in ``__post_init__`` with :func:`check_fields`, which
checks each field as the field declares it:

* :func:`ranged` declares the numbers a field accepts, a :class:`prg.checks.Range`, once: the
  dataclass refuses a value outside it (``impute_steps must be an integer in [0, 1000], got
  -1``) and :data:`prg.checks.RANGES` takes the config option's entry from the same declaration
  (:func:`declared_ranges`; ``generate.impute_steps``), so the settings class and the config
  check cannot drift apart; a field of several numbers declares the range of each
  (``ranged(..., items=2)``: ``paper.size_cm``; ``keyed=True``: ``robot.held_joints.*``);
* :func:`checked` declares a check-and-convert function (the converted value is stored).

Classes not yet declaring their fields use the one-field checks below (:func:`positive`,
:func:`at_least`, :func:`vector` ...) or :func:`check_ranges` with a table of
:mod:`prg.checks`. This module imports no numpy, so that the settings classes that declare their
ranges can be read by the config check before any heavy library is loaded. An error
names the field as the dataclass spells it (``lift_cm must be a finite number in (0, 100], got
0``); whoever
read the value from a config tree adds its path with :meth:`~prg.errors.SettingsError.under`
(``motion.lift_cm ...``). :class:`FromMapping` gives a settings dataclass ``from_mapping``: its
fields from a plain mapping (a YAML node), unknown keys refused, lists taken as tuples.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import numbers
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any, TypeVar

from prg.errors import SettingsError, UsageError

if TYPE_CHECKING:
    from prg.checks import Range

__all__ = [
    "FromMapping",
    "as_float",
    "at_least",
    "check",
    "check_fields",
    "check_ranges",
    "checked",
    "declared_ranges",
    "integer",
    "listed_as_tuple",
    "number",
    "positive",
    "positive_float",
    "positive_integer",
    "ranged",
    "vector",
]

_Settings = TypeVar("_Settings", bound="FromMapping")


def integer(value: Any, field: str, minimum: int = 1) -> int:
    """``value`` as an ``int`` when it is an integer (not a bool) of at least ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < minimum:
        raise SettingsError(field, f"must be an integer >= {minimum}, got {value!r}")
    return int(value)


def number(value: Any, field: str, minimum: float | None = None, *, strict: bool = False) -> float:
    """``value`` as a finite ``float``, at least ``minimum`` (above it when ``strict``)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise SettingsError(field, f"must be a number, got {value!r}")
    value = float(value)
    if minimum is None:
        low, bound = True, ""
    else:
        low = value > minimum if strict else value >= minimum
        bound = f" {'>' if strict else '>='} {minimum}"
    if not (math.isfinite(value) and low):
        raise SettingsError(field, f"must be a finite number{bound}, got {value!r}")
    return value


def checked(default: Any, check: Callable[..., Any], **options: Any) -> Any:
    """A dataclass field with ``default`` whose value ``check(value, name, **options)`` checks
    and converts (:func:`check_fields`)."""
    return dataclasses.field(
        default=default, metadata={"check": functools.partial(check, **options)}
    )


def ranged(default: Any, spec: Range, *, items: bool | int = False, keyed: bool = False) -> Any:
    """A dataclass field with ``default`` that accepts the numbers of ``spec`` (a
    :class:`prg.checks.Range`): :func:`check_fields` refuses any other value, and
    :func:`declared_ranges` gives ``spec`` to the config check (:data:`prg.checks.RANGES`).

    A field holding several numbers, each in ``spec``: ``items=True`` a sequence of any length,
    ``items=N`` of exactly ``N`` (stored as a tuple; the config check takes each item of the
    option's list), ``keyed=True`` a mapping of names to numbers (stored as a dict with ``str``
    keys; the config option is ``NODE.FIELD.*``). ``default`` may be
    :data:`dataclasses.MISSING` (a field the caller must give); a keyed field's default is a
    mapping, copied for each instance.

    Examples
    --------
    >>> from dataclasses import dataclass
    >>> from prg.checks import count
    >>> @dataclass(frozen=True)
    ... class Steps:
    ...     steps: int = ranged(20, count(0, 1000))
    ...
    ...     def __post_init__(self) -> None:
    ...         check_fields(self)
    >>> Steps(-1)
    Traceback (most recent call last):
    prg.errors.SettingsError: steps must be an integer in [0, 1000], got -1
    >>> declared_ranges(Steps, "walk") == {"walk.steps": count(0, 1000)}
    True
    """
    metadata = {"range": spec, "items": items, "keyed": keyed}
    if keyed and default is not dataclasses.MISSING:
        return dataclasses.field(default_factory=lambda: dict(default), metadata=metadata)
    return dataclasses.field(default=default, metadata=metadata)


def check_fields(settings: Any) -> None:
    """Check the declared fields of a (frozen) dataclass instance, in declaration order: a
    :func:`checked` field's value is checked and its converted value stored, a :func:`ranged`
    field's value must lie in its range (the first refused raises
    :class:`~prg.errors.SettingsError` naming the field)."""
    from prg.checks import require_number

    for field in dataclasses.fields(settings):
        check = field.metadata.get("check")
        if check is not None:
            value = check(getattr(settings, field.name), field.name)
            object.__setattr__(settings, field.name, value)
        spec = field.metadata.get("range")
        if spec is None:
            continue
        value = getattr(settings, field.name)
        items, keyed = field.metadata.get("items", False), field.metadata.get("keyed", False)
        if keyed:
            object.__setattr__(settings, field.name, _keyed(value, field.name, spec))
        elif items is not False:
            size = None if items is True else items
            object.__setattr__(settings, field.name, _items(value, field.name, spec, size))
        else:
            require_number(value, field.name, spec)


def _item(value: Any, spec: Range) -> Any:
    """One number of a several-number field as :class:`~prg.checks.Range` reads it (a numpy
    scalar as an ``int`` or a ``float``), or None when ``spec`` does not accept it."""
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        value = int(value)
    elif isinstance(value, numbers.Real) and not isinstance(value, bool):
        value = float(value)
    if value is None or not spec.accepts(value):
        return None
    return value if spec.integer else float(value)


def _items(value: Any, field: str, spec: Range, size: int | None) -> tuple:
    """``value`` as a tuple of ``size`` (any number when None) numbers, each in ``spec``; a
    refused item is named as the config check names it (``size_cm[0] must be ...``)."""
    from prg.checks import _short

    count = "a list of numbers" if size is None else f"a list of {size} numbers"
    given: tuple | None = None
    if not isinstance(value, str | bytes | Mapping):
        try:
            given = tuple(value)
        except TypeError:
            given = None
    if given is None or (size is not None and len(given) != size):
        raise SettingsError(field, f"must be {count}, got {_short(value)}")
    checked_items = []
    for i, item in enumerate(given):
        checked_item = _item(item, spec)
        if checked_item is None:
            raise SettingsError(f"{field}[{i}]", f"must be {spec.describe()}, got {_short(item)}")
        checked_items.append(checked_item)
    return tuple(checked_items)


def _keyed(value: Any, field: str, spec: Range) -> dict[str, Any]:
    """``value`` (None: empty) as a dict of names to numbers, each in ``spec``."""
    from prg.checks import _short

    value = {} if value is None else value
    if not isinstance(value, Mapping):
        raise SettingsError(field, f"must map names to numbers, got {_short(value)}")
    out = {}
    for key, item in value.items():
        checked_item = _item(item, spec)
        if checked_item is None:
            raise SettingsError(f"{field}.{key}", f"must be {spec.describe()}, got {_short(item)}")
        out[str(key)] = checked_item
    return out


def declared_ranges(settings_class: type, prefix: str = "") -> dict[str, Range]:
    """The :func:`ranged` fields of a settings dataclass, field name to range, each name after
    ``prefix`` and a dot when a prefix is given (the config node that holds the fields); a keyed
    field's name ends in ``.*`` (one option per key)."""
    start = f"{prefix}." if prefix else ""
    return {
        f"{start}{field.name}{'.*' if field.metadata.get('keyed') else ''}": field.metadata["range"]
        for field in dataclasses.fields(settings_class)
        if "range" in field.metadata
    }


def check(ok: bool, field: str, problem: str) -> None:
    """Raise ``SettingsError(field, problem)`` unless ``ok``."""
    if not ok:
        raise SettingsError(field, problem)


def as_float(value: Any, field: str) -> float:
    """``value`` as a float, not yet checked to be finite; a bool, a string or anything else not
    a number is refused."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise SettingsError(field, f"must be a number, got {value!r}")
    return float(value)


def positive(owner: Any, *fields: str, what: str = "positive") -> None:
    """Each of ``owner``'s ``fields`` is a finite number > 0 (else: ``must be WHAT, got ...``)."""
    for field in fields:
        value = getattr(owner, field)
        x = as_float(value, field)
        check(math.isfinite(x) and x > 0, field, f"must be {what}, got {value!r}")


def positive_float(value: Any, field: str, what: str = "positive") -> float:
    """``value`` as a float > 0 (else: ``must be WHAT, got VALUE`` with the value as a float)."""
    x = as_float(value, field)
    check(math.isfinite(x) and x > 0, field, f"must be {what}, got {x!r}")
    return x


def at_least(owner: Any, field: str, low: float = 0.0) -> None:
    """``owner.field`` is a finite number >= ``low`` (else: ``must be >= LOW, got ...``)."""
    value = getattr(owner, field)
    x = as_float(value, field)
    check(math.isfinite(x) and x >= low, field, f"must be >= {low:g}, got {value!r}")


def positive_integer(owner: Any, *fields: str) -> None:
    """Each of ``owner``'s ``fields`` is a whole number >= 1 (``4.0`` is accepted)."""
    for field in fields:
        value = getattr(owner, field)
        x = as_float(value, field)
        ok = math.isfinite(x) and x.is_integer() and x >= 1
        check(ok, field, f"must be a positive integer, got {value!r}")


def vector(value: Any, field: str, size: int, problem: str) -> tuple[float, ...]:
    """``value`` as a tuple of ``size`` finite floats (else: ``PROBLEM, got ...``)."""
    import numpy as np  # not at the top: the config check imports this module

    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise SettingsError(field, f"{problem}, got {value!r}") from None
    check(
        arr.shape == (size,) and bool(np.all(np.isfinite(arr))), field, f"{problem}, got {value!r}"
    )
    return tuple(float(v) for v in arr)


class FromMapping:
    """Mixin for a settings dataclass: :meth:`from_mapping` builds it from a plain mapping."""

    @classmethod
    def from_mapping(cls: type[_Settings], values: Mapping[str, Any] | None) -> _Settings:
        """The settings from ``values`` (field name to value; a missing field keeps its default).

        Lists become tuples. Raises :class:`~prg.errors.SettingsError` naming the field: one
        that is not a field of this class, or a value the class refuses.
        """
        if values is None:
            return cls()
        if not isinstance(values, Mapping):
            raise UsageError(
                f"{cls.__name__}: expected a mapping of settings, got {type(values).__name__}"
            )
        names = [f.name for f in dataclasses.fields(cls) if f.init]  # type: ignore[arg-type]
        for key in values:
            check(key in names, str(key), f"is not a setting here: accepted are {', '.join(names)}")
        return cls(**{k: listed_as_tuple(v) for k, v in values.items()})


def listed_as_tuple(value: Any) -> Any:
    """A list (as YAML gives it) as a tuple (as the dataclasses hold it); anything else as is."""
    return tuple(value) if isinstance(value, list) else value


def check_ranges(settings: Any, ranges: Mapping[str, Any]) -> None:
    """Refuse the first field of a settings dataclass outside its :class:`~prg.checks.Range` in
    ``ranges`` (field name to range; the tables live in :mod:`prg.checks`, which also checks
    the config options with them)."""
    from prg.checks import require_number

    for name, spec in ranges.items():
        require_number(getattr(settings, name), name, spec)
