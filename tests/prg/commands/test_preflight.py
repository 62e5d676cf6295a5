"""The one line for a command line that does not compose (prg.commands.preflight), in process:
the lines the commands print are in tests/cli/test_bad_inputs.py."""

from __future__ import annotations

import pytest

from prg.commands.cli import compose_config
from prg.commands.preflight import composition_error
from prg.resources import config_dir


def line_for(config_name: str, overrides: list[str]) -> str:
    """The line for ``overrides``, from the error composing them raises."""
    with pytest.raises(Exception) as failed:  # Hydra raises several types
        compose_config(config_name, overrides)
    return composition_error(failed.value, config_name, overrides)


def test_one_unknown_key_names_the_closest_and_the_keys_accepted_there():
    line = line_for("write", ["generate.temprature=1"])
    assert line.startswith("unknown key generate.temprature (closest: generate.temperature")
    accepted = line.partition("accepted under generate: ")[2].split(", ")
    assert set(accepted) == set(compose_config("write", []).generate)


def test_every_unknown_key_is_named_and_the_accepted_keys_are_the_composable_rests():
    line = line_for("write", ["colr=2", "text=hi", "wdth=3", "generate.mode=hand"])
    first, _, also = line.partition(" (also unknown: ")
    assert first.startswith("unknown key colr; accepted top-level keys: ")
    assert also == "wdth)"
    accepted = first.partition("accepted top-level keys: ")[2].split(", ")
    assert set(accepted) == set(compose_config("write", ["text=hi"]))


def test_a_config_group_of_another_command_is_an_unknown_key():
    line = line_for("write", ["model=muse"])
    assert line.startswith("unknown key model (closest: ")
    assert "accepted top-level keys: text," in line


def test_a_key_in_capitals_is_said_to_be_an_environment_variable():
    assert line_for("write", ["PRG_ROOT=/x"]).endswith(
        "; PRG_ROOT looks like an environment variable: put it before the command"
    )
    assert "environment variable" not in line_for("write", ["Text=hi"])


def test_an_unknown_group_option_is_answered_first_with_the_options():
    """Hydra reads the defaults list before the keys: the group's option is the line."""
    options = sorted(p.stem for p in (config_dir() / "model").glob("*.yaml") if p.stem[0] != "_")
    line = line_for("train", ["seeed=1", "model=musee"])
    assert line == f"unknown model musee; accepted: {', '.join(options)}"


@pytest.mark.parametrize(
    "override, reason",
    [
        ("text=a=b", "mismatched input '='"),
        ("generate.seed=[1", "no viable alternative at input '[1'"),
        ("text=héllo", "token recognition error at: 'é'"),
        ("text=(hi", "extraneous input '('"),
    ],
)
def test_an_override_the_grammar_cannot_read_is_named_with_the_reason(override, reason):
    line = line_for("write", ["text=fine", override])
    assert line.startswith(f"cannot read {override}: {reason}")
    assert "expecting {" not in line  # not the grammar's list of every token


def test_an_unknown_key_no_override_names_ends_in_hydras_message():
    """A failure about a key the overrides do not spell the same way (nothing to drop) is
    answered with Hydra's own line, not looped on."""
    from hydra.errors import ConfigCompositionException

    err = ConfigCompositionException("Could not override 'nowhere'. No match in the defaults list.")
    line = composition_error(err, "write", ["text=hi", "colr=1"])
    assert line == "Could not override 'nowhere'. No match in the defaults list."
