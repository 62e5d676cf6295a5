"""The study's ``robot.write_overrides`` as writing settings: the ``prg-write`` options a study
may set (``generate.*``, ``layout.*``, ``connection.*``, ``marks.*``, ``style``, ``on_unknown``,
``threads``) read from their ``key=value`` texts onto a
:class:`~prg.pipeline.compose.GenerateSettings`, without composing ``prg-write``'s config.

The defaults are ``conf/write.yaml``'s (the same as ``GenerateSettings()``'s); values are read as
``prg-write`` reads them (``null``, ``true``/``false``, numbers, quoted or bare text, ``[a,b]``
lists) and checked by the same ranges (:func:`prg.checks.check_values`) and settings classes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, fields
from typing import Any

from prg.errors import SettingsError, UsageError

#: Options of ``prg-write`` outside the settings sections that a study may set.
WRITER_OPTIONS = {"style": None, "on_unknown": "error", "threads": 1}


@dataclass(frozen=True)
class WriteSettings:
    """How the study's robot writes: the :class:`~prg.writer.Writer`'s settings and options.

    Attributes
    ----------
    generate : GenerateSettings
    style : str or None
        A person's letters to write in their hand (``prg-write``'s ``style``).
    on_unknown : str
        ``"error"`` or ``"skip"``: characters outside 0-9, A-Z, a-z.
    threads : int
        Torch threads for decoding (``prg-write``'s ``threads``, 1 by default).
    """

    generate: Any
    style: str | None = None
    on_unknown: str = "error"
    threads: int = 1


def sets_delayed_strokes(override: str) -> bool:
    """Whether a ``prg-write`` override sets ``delayed_strokes`` (``delayed_strokes=...``,
    ``+``/``++``/``~`` forms too)."""
    key = override.partition("=")[0].strip().lstrip("+~").strip()
    return key == "delayed_strokes"


def override_value(text: str) -> Any:
    """An override's value as ``prg-write`` reads it: ``null``, ``true``/``false``, an int, a
    float, a quoted or bare string, or a ``[a, b]`` list of these."""
    t = text.strip()
    if t.lower() == "null":
        return None
    if t.lower() in ("true", "false"):
        return t.lower() == "true"
    for cast in (int, float):
        try:
            return cast(t)
        except ValueError:
            pass
    if len(t) >= 2 and t[0] == t[-1] and t[0] in "'\"":
        return t[1:-1]
    if t.startswith("[") and t.endswith("]"):
        inner = t[1:-1].strip()
        return [override_value(item) for item in inner.split(",")] if inner else []
    return t


def _sections() -> dict[str, dict[str, Any]]:
    """The settings sections with their defaults (``connection`` without ``alpha_max``: it is
    given in degrees, ``alpha_max_deg``, and only when overridden)."""
    from prg.pipeline.compose import GenerateSettings

    base = GenerateSettings()
    nested = {"marks", "layout", "connection", "delayed_strokes"}
    generate = {f.name: getattr(base, f.name) for f in fields(base) if f.name not in nested}
    connection = asdict(base.connection)
    connection.pop("alpha_max")
    return {
        "generate": generate,
        "marks": asdict(base.marks),
        "layout": asdict(base.layout),
        "connection": connection,
    }


def write_settings(
    overrides: Sequence[str], delayed_strokes: bool = True, family: str = "muse"
) -> WriteSettings:
    """The robot's writing settings: ``prg-write``'s defaults with ``overrides`` applied.

    Parameters
    ----------
    overrides : sequence of str
        ``key=value`` texts (``generate.temperature=0.3``); ``+key=value`` too.
    delayed_strokes : bool
    family : str
        Checked against the model families, as ``prg-write`` checks it.

    Raises
    ------
    UsageError
        An override that is not ``key=value``, names no setting a study may set, or gives a
        value its setting refuses (named under ``robot.write_overrides``).
    """
    from prg.checks import check_values
    from prg.pipeline.compose import GenerateSettings
    from prg.pipeline.connect import ConnectionSettings
    from prg.pipeline.layout import LayoutSettings
    from prg.pipeline.marks import MarkSettings

    sections = _sections()
    options = dict(WRITER_OPTIONS)
    given: dict[str, dict[str, Any]] = {}  # the overridden values, checked by their ranges
    degrees = None
    for text in overrides:
        key, eq, raw = text.partition("=")
        key = key.strip().lstrip("+").strip()
        section, _, name = key.partition(".")
        value = override_value(raw)
        if not eq or not key or key.startswith("~"):
            problem = "not a key=value override"
        elif key in options:
            options[key] = value
            continue
        elif key == "connection.alpha_max_deg":
            if isinstance(value, bool) or not isinstance(value, int | float):
                problem = f"connection.alpha_max_deg must be a number, got {value!r}"
            else:
                degrees = value
                given.setdefault(section, {})[name] = value
                continue
        elif section in sections and name in sections[section]:
            sections[section][name] = value
            given.setdefault(section, {})[name] = value
            continue
        else:
            accepted = ", ".join([*(f"{s}.*" for s in sections), *options])
            problem = f"no setting {key} a study may set (accepted: {accepted})"
        raise UsageError(f"robot.write_overrides: {text!r}: {problem}")
    try:
        check_values({"family": family, **given})
        connection = dict(sections["connection"])
        if degrees is not None:
            connection["alpha_max"] = math.radians(degrees)
        parts = {}
        for key, cls in (
            ("marks", MarkSettings),
            ("layout", LayoutSettings),
            ("connection", ConnectionSettings),
        ):
            try:
                parts[key] = cls(**(connection if key == "connection" else sections[key]))
            except SettingsError as err:
                raise err.under(key) from None
        try:
            generate = GenerateSettings(
                **sections["generate"], delayed_strokes=delayed_strokes, **parts
            )
        except SettingsError as err:
            raise err.under("generate") from None
        return WriteSettings(generate, **options)
    except (UsageError, TypeError) as err:
        raise UsageError(f"robot.write_overrides: {err}") from None
