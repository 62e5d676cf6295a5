"""Tests of ``prg.commands.settings`` (moved from the suite on: stimuli: reading robot and human
samples, and drawing every one of them alike)."""

from __future__ import annotations

import pytest


@pytest.mark.parametrize(
    "overrides",
    [
        [],
        ["generate.temperature=0.3", "generate.mode=posterior"],
        ["generate.hand_seed=3", "layout.gap=0.3", "marks.dotted=j"],
        ["connection.alpha_max_deg=25", "++generate.impute_steps=10"],
    ],
)
def test_the_robot_writes_with_prg_writes_settings(overrides):
    from prg.commands.cli import compose_config
    from prg.commands.settings import generate_settings
    from studies.stimuli import write_settings

    for delayed in (True, False):
        args = ["family=muse", f"delayed_strokes={str(delayed).lower()}", *overrides]
        expected = generate_settings(compose_config("write", args))
        assert write_settings(overrides, delayed).generate == expected
