"""Fast answers: a bad command line is answered from the composed config before torch is
imported, with the accepted keys or values; ``--help`` says what each command does, its main
options and an example that composes. (Timings live in ``benchmarks/bench_startup.py``.)"""

from __future__ import annotations

import re
import sys

import pytest
from omegaconf import OmegaConf

from prg.checks import FAMILIES
from prg.commands.cli import compose_config
from prg.resources import config_dir
from tests.cli.test_bad_inputs import HYDRA_COMMANDS, entry_point, restore_logging  # noqa: F401
from tests.conftest import run_cli


def imported_modules(stderr: str) -> set[str]:
    """The modules ``-X importtime`` (PYTHONPROFILEIMPORTTIME) reports in ``stderr``."""
    return {
        line.rpartition("|")[2].strip() for line in stderr.splitlines() if "import time:" in line
    }


@pytest.mark.parametrize(
    "args, expected",
    [
        (["txt=hello"], "prg-write: error: unknown key txt (closest: text); accepted top-level"),
        (
            ["family=musee"],
            "prg-write: error: unknown family musee; accepted: cvae, avae_ts, avae_ti, muse",
        ),
        (["generate.temperature=-1"], "prg-write: error: generate.temperature must be"),
        (
            ["text=hi", "generate.method=curvy"],
            "prg-write: error: unknown connection method curvy; accepted: hand, alg1, straight",
        ),
        (["--help"], None),
    ],
    ids=[
        "unknown-key",
        "unknown-family",
        "out-of-range",
        "unknown-method",
        "help",
    ],
)
def test_prg_write_answers_before_importing_torch_and_writes_nothing(tmp_path, args, expected):
    env = {"PYTHONPROFILEIMPORTTIME": "1", "PRG_ROOT": str(tmp_path / "root")}
    result = run_cli("prg-write", *args, cwd=tmp_path, env=env)
    modules = imported_modules(result.stderr)
    assert "prg.commands.entry" in modules  # the report is there
    assert {"torch", "numpy", "scipy", "lightning", "mlflow", "rerun"}.isdisjoint(modules)
    said = [line for line in result.stderr.splitlines() if "import time:" not in line]
    if expected is None:
        assert result.returncode == 0 and said == [] and "Example:" in result.stdout
    else:
        assert result.returncode == 2 and len(said) == 1 and said[0].startswith(expected), said
    assert list(tmp_path.iterdir()) == []  # not even Hydra's run folder: nothing ran


def test_the_known_families_are_the_model_configs():
    assert sorted(FAMILIES) == sorted(p.stem for p in (config_dir() / "model").glob("*.yaml"))


def _help_of(command: str, monkeypatch, capfd) -> str:
    monkeypatch.setattr(sys, "argv", [command, "--help"])
    capfd.readouterr()
    try:
        entry_point(command)()
    except SystemExit as exit:
        assert exit.code in (None, 0)
    out, err = capfd.readouterr()
    assert err == ""
    return out


@pytest.mark.parametrize("command", HYDRA_COMMANDS)
def test_help_says_what_the_command_does_its_options_and_an_example_that_composes(
    command,
    monkeypatch,
    capfd,
    restore_logging,
    tmp_path,
):
    monkeypatch.setenv("PRG_ROOT", str(tmp_path))
    text = _help_of(command, monkeypatch, capfd)
    config = command.removeprefix("prg-")
    lines = text.splitlines()
    assert re.match(rf"{command}: \w", lines[0]), lines[0]  # what it does, in one line
    assert "Powered by Hydra" not in text  # not Hydra's generic help
    assert str(tmp_path) in text  # where its files go
    example = lines[lines.index("Example:") + 1].split()
    assert example[0] == command
    cfg = compose_config(config, example[1:])  # the example is a valid command line
    options = text[text.index("Main options:") : text.index("Example:")]
    keys = re.findall(r"(?:^|\s)\+?([a-z_][\w.]*)=", options)
    assert len(keys) >= 4
    groups = {p.name for p in config_dir().iterdir() if p.is_dir()}
    for key in keys:  # every option it names exists (or is a config group, or a new name's parent)
        parent = key.rpartition(".")[0]
        known = OmegaConf.select(cfg, key, default="?missing") != "?missing"
        assert known or key in groups or OmegaConf.select(cfg, parent) is not None, key


def _accepted(module: str, name: str) -> list[str]:
    import importlib

    return list(getattr(importlib.import_module(module), name))


@pytest.mark.parametrize(
    "command, listed, accepted",
    [
        ("prg-write", "family=", FAMILIES),
        ("prg-write", "generate.mode=", ("prg.pipeline.settings", "DECODING_MODES")),
        ("prg-write", "generate.method=", ("prg.pipeline.settings", "CONNECTION_METHODS")),
        ("prg-write", "generate.timing=", ("prg.pipeline.settings", "TIMINGS")),
        ("prg-write", "speech.backend=", ("prg.pipeline.speech.settings", "BACKENDS")),
        ("prg-evaluate", "parts=[", ("prg.evaluation.settings", "PARTS")),
    ],
    ids=lambda value: value if isinstance(value, str) else None,
)
def test_help_lists_the_accepted_values_of_its_choices(
    command, listed, accepted, monkeypatch, capfd, restore_logging, tmp_path
):
    """A choice the help spells out (``generate.method=hand|alg1|straight``) names exactly the
    values the command accepts, so a new value cannot go unmentioned (``parts``: the reports;
    training the classifiers is said in words)."""
    monkeypatch.setenv("PRG_ROOT", str(tmp_path))
    text = _help_of(command, monkeypatch, capfd)
    values = re.search(rf"(?:^|[\s(]){re.escape(listed)}([\w|,]+)", text).group(1)
    names = re.split(r"[|,]", values)
    expected = list(FAMILIES) if accepted is FAMILIES else _accepted(*accepted)
    if listed == "parts=[":
        expected.remove("classifiers")
    assert names == expected


@pytest.mark.parametrize("command", [c for c in HYDRA_COMMANDS if c != "prg-write"])
def test_every_command_answers_a_typo_before_importing_its_task(tmp_path, command):
    """The console scripts are made in prg.commands.entry, which names each task by its module:
    the module (and torch, Lightning, MLflow with it) is imported only once the command line
    is checked."""
    env = {"PYTHONPROFILEIMPORTTIME": "1", "PRG_ROOT": str(tmp_path / "root")}
    result = run_cli(command, "txt=hello", cwd=tmp_path, env=env)
    modules = imported_modules(result.stderr)
    assert "prg.commands.entry" in modules  # the report is there
    task_module = f"prg.commands.{command.removeprefix('prg-')}"
    assert {task_module, "torch", "lightning", "mlflow", "rerun"}.isdisjoint(modules)
    said = [line for line in result.stderr.splitlines() if "import time:" not in line]
    assert result.returncode == 2 and len(said) == 1, said
    assert said[0].startswith(f"{command}: error: unknown key txt"), said
    assert list(tmp_path.iterdir()) == []
