"""Analysis options: read defensively from the study YAML, overridden from the command line.

The study configs (``conf/study/turing.yaml``, ``conf/study/readability.yaml``) are written for
the whole study (design, stimuli, web page); the analysis reads only the keys it knows, at the
top level or under an ``analysis:`` node, and ignores the rest:

``kind``              ``turing`` | ``readability``
``name``              the study's name (report title)
``equivalence_margin`` the equivalence / non-inferiority margin (rate scale)
``margin_source``     ``preregistered`` | ``data``: where the margin came from
``alpha``             significance level (default 0.05)
``chance``            chance rate of picking the robot (default ``1 / n_options`` = 0.2)
``n_options``         samples shown per Turing trial (default 5; or ``foils`` + 1)
``neutral``           the neutral confidence rating (default 3)
``words``             the study's words (used by the simulator)
``exclude_failed_attention`` drop participants who failed an attention check (default true)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from prg.errors import UsageError
from studies.analysis.schema import N_OPTIONS, READABILITY, STUDY_KINDS, TURING, study_kind

DEFAULT_MARGIN = {TURING: 0.05, READABILITY: 0.10}
MARGIN_SOURCES = ("preregistered", "data", "unstated", "default")


@dataclass(frozen=True)
class AnalysisSettings:
    """Options of one analysis run (see the module docstring for the YAML keys)."""

    kind: str | None = None
    name: str | None = None
    margin: float | None = None  #: None: the per-study default (0.05 Turing, 0.10 readability)
    margin_source: str = (
        "default"  #: preregistered | data | unstated (margin given, source not) | default
    )
    alpha: float = 0.05
    chance: float = 1.0 / N_OPTIONS
    n_options: int = N_OPTIONS
    neutral: float = 3.0
    words: tuple[str, ...] = ()
    include_attention_rows: bool = False
    exclude_failed_attention: bool = True
    mixed_model: bool = True
    source: str | None = None  #: the YAML file read, for the report
    notes: tuple[str, ...] = field(default=())  #: what was read defensively (unknown values...)

    def margin_for(self, kind: str) -> float:
        """The margin for ``kind``: the configured one, else the per-study default."""
        return self.margin if self.margin is not None else DEFAULT_MARGIN[kind]


def _number(value: Any, key: str, path: str, low: float, high: float) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise UsageError(
            f"{path}: {key} {value!r} is not a number (accepted: {low}-{high})"
        ) from None
    if not (math.isfinite(x) and low < x < high):
        raise UsageError(f"{path}: {key} {value!r} is outside ({low}, {high})")
    return x


def load_config(path: str | Path | None) -> AnalysisSettings:
    """Read the analysis options from a study YAML (``None``: all defaults).

    Raises
    ------
    prg.errors.UsageError
        The file is missing, is not YAML, or a known key has a value out of range.
    """
    if path is None:
        return AnalysisSettings()
    import yaml

    p = Path(path)
    if not p.is_file():
        raise UsageError(
            f"{path}: no such study config (expected a YAML file like conf/study/turing.yaml)"
        )
    try:
        raw = yaml.safe_load(p.read_text(encoding="utf-8"))
    except yaml.YAMLError as err:
        line = getattr(getattr(err, "problem_mark", None), "line", None)
        where = f" line {line + 1}" if line is not None else ""
        raise UsageError(f"{path}{where}: not valid YAML") from None
    if raw is None:
        raw = {}
    if not isinstance(raw, dict):
        raise UsageError(
            f"{path}: expected a mapping of keys (name, kind, equivalence_margin, ...)"
        )
    node = dict(raw)
    if isinstance(raw.get("analysis"), dict):
        node.update(raw["analysis"])  # an analysis: node wins over the top level
    return config_from_mapping(node, str(path))


def config_from_mapping(node: dict[str, Any], path: str = "config") -> AnalysisSettings:
    """Build the options from a plain mapping (the YAML's keys); unknown keys are ignored."""
    notes: list[str] = []
    kind = None
    if node.get("kind") is not None:
        kind = study_kind(str(node["kind"]))
        if kind is None:
            raise UsageError(
                f"{path}: kind {node['kind']!r} is not one of {', '.join(STUDY_KINDS)}"
            )
    n_options = N_OPTIONS
    if node.get("n_options") is not None:
        n_options = int(_number(node["n_options"], "n_options", path, 1, 1000))
    elif node.get("foils") is not None:
        n_options = int(_number(node["foils"], "foils", path, 0, 1000)) + 1
    chance = 1.0 / n_options
    if node.get("chance") is not None:
        chance = _number(node["chance"], "chance", path, 0, 1)
    alpha = 0.05
    if node.get("alpha") is not None:
        alpha = _number(node["alpha"], "alpha", path, 0, 0.5)
    margin = None
    margin_key = next(
        (k for k in ("equivalence_margin", "margin", "delta") if node.get(k) is not None), None
    )
    if margin_key is not None:
        margin = _number(node[margin_key], margin_key, path, 0, 1)
    source = "default" if margin is None else "unstated"
    if node.get("margin_source") is not None:
        source = str(node["margin_source"]).strip().lower()
        if source not in MARGIN_SOURCES[:2]:
            raise UsageError(
                f"{path}: margin_source {node['margin_source']!r} is not one of preregistered, data"
            )
    elif margin is not None:
        notes.append(f"{path} gives a margin but no margin_source (preregistered or data)")
    neutral = 3.0
    if node.get("neutral") is not None:
        neutral = _number(node["neutral"], "neutral", path, 1 - 1e-9, 5 + 1e-9)
    words = node.get("words") or ()
    if isinstance(words, str):
        words = [w for w in words.replace(",", " ").split() if w]
    exclude = node.get("exclude_failed_attention", True)
    if not isinstance(exclude, bool):
        raise UsageError(f"{path}: exclude_failed_attention must be true or false, got {exclude!r}")
    return AnalysisSettings(
        kind=kind,
        name=str(node["name"]) if node.get("name") is not None else None,
        margin=margin,
        margin_source=source,
        alpha=alpha,
        chance=chance,
        n_options=n_options,
        neutral=neutral,
        words=tuple(str(w) for w in words) if isinstance(words, list | tuple) else (),
        exclude_failed_attention=bool(exclude),
        source=path,
        notes=tuple(notes),
    )


def with_overrides(cfg: AnalysisSettings, **overrides: Any) -> AnalysisSettings:
    """``cfg`` with the command line's values (``None`` means: not given) checked and applied."""
    given = {k: v for k, v in overrides.items() if v is not None}
    if "margin_source" in given and given["margin_source"] not in MARGIN_SOURCES[:2]:
        raise UsageError(
            f"--margin-source {given['margin_source']!r} is not one of preregistered, data"
        )
    if "margin" in given:
        _number(given["margin"], "--margin", "command line", 0, 1)
        given.setdefault("margin_source", "unstated")
    if "alpha" in given:
        _number(given["alpha"], "--alpha", "command line", 0, 0.5)
    if "chance" in given:
        _number(given["chance"], "--chance", "command line", 0, 1)
        options = 1.0 / given["chance"]
        if abs(options - round(options)) < 1e-6:  # chance 1/k: k samples per trial
            given.setdefault("n_options", round(options))
    if "kind" in given and given["kind"] not in (TURING, READABILITY):
        raise UsageError(f"study kind {given['kind']!r} is not one of {', '.join(STUDY_KINDS)}")
    return replace(cfg, **given)
