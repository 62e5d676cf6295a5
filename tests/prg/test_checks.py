"""The accepted ranges of the numeric options (prg.checks): every option has one, every range
refuses NaN, infinity and a value beyond it with one line naming the option, and a text option
keeps the characters typed."""

from __future__ import annotations

import json
import math
import re
import sys

import pytest
from omegaconf import OmegaConf

from prg.checks import RANGES, check_values, leaves, literal_text, literal_words, range_of
from prg.commands.cli import compose_config
from prg.errors import UsageError
from tests.cli.test_bad_inputs import entry_point, restore_logging  # noqa: F401 (fixture)

# Each command's config, and the config groups that add numeric options of their own.
CONFIGS = [
    ("prepare", []),
    ("prepare", ["data=uji"]),
    ("train", []),
    ("train", ["model=cvae"]),
    ("train", ["model=avae_ti", "experiment=quick"]),
    ("train", ["model=avae_ts", "experiment=converged"]),
    ("train", ["experiment=paper", "trainer=ddp"]),
    ("evaluate", []),
    ("write", []),
    ("dictaphone", []),
    ("simulate", []),
    ("simulate", ["robot=iiwa"]),
    ("export", []),
    ("export", ["robot=iiwa"]),
]


def _numeric(value) -> bool:
    items = value if isinstance(value, list) else [value]
    return any(isinstance(v, int | float) and not isinstance(v, bool) for v in items)


@pytest.mark.parametrize("name, overrides", CONFIGS, ids=[" ".join([n, *o]) for n, o in CONFIGS])
def test_every_numeric_option_has_a_range_and_its_default_is_in_it(name, overrides):
    cfg = compose_config(name, overrides)
    numeric = [k for k, v in leaves(OmegaConf.to_container(cfg, resolve=True)) if _numeric(v)]
    assert numeric
    assert [k for k in numeric if range_of(k) is None] == []
    check_values(cfg)  # the shipped defaults are accepted


def _concrete(pattern: str) -> str:
    return pattern.replace("*", "x")


def _outside(spec) -> list:
    """Values the range must refuse."""
    values = [math.nan, math.inf, -math.inf, "ten", True]
    if spec.low is not None:
        below = spec.low if spec.low_open else spec.low - 1
        values.append(below - 1 if below in spec.also else below)  # -1: "no limit" for some
    if spec.high is not None:
        values.append(spec.high if spec.high_open else spec.high + 1)
    if spec.integer:
        values.append(1.5)
    if not spec.optional:
        values.append(None)
    return values


def _nested(key: str, value) -> dict:
    node: dict = {}
    inner = node
    *parents, last = key.split(".")
    for part in parents:
        inner = inner.setdefault(part, {})
    inner[last] = value
    return node


@pytest.mark.parametrize("pattern", sorted(RANGES))
def test_each_range_refuses_what_lies_outside_it_naming_the_option(pattern):
    key, spec = _concrete(pattern), RANGES[pattern]
    for value in _outside(spec):
        if spec.text and isinstance(value, str):
            continue
        with pytest.raises(UsageError, match="^" + re.escape(f"{key} must be ")):
            check_values(_nested(key, value))


def test_a_list_option_names_the_element_out_of_range():
    with pytest.raises(
        UsageError, match=r"^paper\.size_cm\[0\] must be a finite number in \(0, 1000\]"
    ):
        check_values({"paper": {"size_cm": [0.0, 29.7]}})


def test_literal_text_without_a_command_line_asks_for_quotes():
    assert literal_text("true", "text") == "true"
    assert literal_text(None, "text") is None
    with pytest.raises(UsageError, match=r"text=True was read as a boolean.*quote it"):
        literal_text(True, "text")
    with pytest.raises(UsageError, match=r"words\[1\]=7 was read as a number, not a word"):
        literal_words(["cat", 7], "words")


@pytest.mark.parametrize("typed", ["true", "1e3", "007"])
def test_text_is_written_as_typed_not_as_hydra_types_it(
    typed,
    tmp_path,
    monkeypatch,
    untrained_muse_checkpoint,
    restore_logging,
):
    out = tmp_path / "out"
    argv = [
        f"paths.root_dir={tmp_path}",
        f"ckpt={untrained_muse_checkpoint}",
        "mlflow=false",
        "record=false",
        f"out_dir={out}",
        f"text={typed}",
    ]
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", ["prg-write", *argv])
    entry_point("prg-write")()
    assert json.loads((out / "word.json").read_text())["text"] == typed
