"""``key=value`` overrides of a study file (``prg-study build --set``): a dotted key names a
nested section, the value is read as YAML (``words=[cat, dog]``, ``page.title="A study"``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import yaml

from prg.errors import UsageError


def parse_override(text: str) -> tuple[list[str], Any]:
    """``"a.b=value"`` -> (["a", "b"], value parsed as YAML); raises :class:`UsageError`."""
    key, sep, value = text.partition("=")
    keys = key.strip().split(".")
    if not sep or not all(k.strip() for k in keys):
        raise UsageError(f"override {text!r} must look like key=value or section.key=value")
    try:
        parsed = yaml.safe_load(value) if value.strip() else None
    except yaml.YAMLError:
        raise UsageError(f"override {text!r}: the value is not valid YAML") from None
    return [k.strip() for k in keys], parsed


def apply_overrides(doc: dict, overrides: Sequence[str]) -> dict:
    """A copy of ``doc`` with ``key=value`` overrides applied (nested keys with dots)."""
    out = yaml.safe_load(yaml.safe_dump(doc))
    for text in overrides:
        keys, value = parse_override(text)
        node = out
        for key in keys[:-1]:
            child = node.get(key)
            if child is None:
                child = node[key] = {}
            if not isinstance(child, dict):
                raise UsageError(f"override {text!r}: {key!r} is not a section")
            node = child
        node[keys[-1]] = value
    return out
