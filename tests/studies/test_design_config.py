"""Tests of ``studies.design_config`` (moved from the suite on: study designs: the YAML files,
Latin-square positions, foils, lists A/B, attention checks)."""

from __future__ import annotations

import pytest

from prg.errors import UsageError
from studies.design import (
    load_study,
    normalise_answer,
)
from tests.helpers.study_design import REPO, WORDS, readability, turing


# ---------------------------------------------------------------------------- the YAML files
def test_the_shipped_studies_follow_the_paper():
    one = load_study(REPO / "conf/study/turing.yaml")
    two = load_study(REPO / "conf/study/readability.yaml")
    assert (one.kind, two.kind) == ("turing", "readability")
    assert len(one.words) == len(two.words) == 10
    assert (one.human_writers, one.foils, one.participants) == (10, 4, 50)
    assert one.chance == pytest.approx(0.2)
    assert (two.participants, two.lists) == (30, ("A", "B"))
    assert one.equivalence_margin == 0.05 and two.equivalence_margin == 0.10
    assert one.attention_checks and two.attention_checks
    assert one.completion["code"] and "{code}" in one.completion["url"]


def test_delayed_strokes_are_on_unless_the_study_file_says_false():
    import yaml

    for name in ("turing", "readability"):
        doc = yaml.safe_load((REPO / f"conf/study/{name}.yaml").read_text())
        assert doc["delayed_strokes"] is True  # written out, not left to the default
        assert load_study(REPO / f"conf/study/{name}.yaml").delayed_strokes is True
        single = load_study(REPO / f"conf/study/{name}.yaml", ["delayed_strokes=false"])
        assert single.delayed_strokes is False
    assert turing().delayed_strokes is True and readability().delayed_strokes is True
    assert turing(delayed_strokes=False).delayed_strokes is False
    assert turing().capture["delayed_max_size"] == 0.35
    assert turing(capture={"delayed_max_size": 0.5}).capture["delayed_max_size"] == 0.5


def test_typed_words_are_compared_as_the_analysis_compares_them():
    from studies.analysis.schema import normalise_text

    for text in ["Cat", "  cat ", "c a t", "CAT\t", "ca  t", ""]:
        assert normalise_answer(text) == normalise_text(text)


def test_overrides_change_nested_settings(tmp_path):
    config = load_study(
        REPO / "conf/study/turing.yaml",
        ["participants=20", "completion.code=ABC123", "words=[cat, dog, sun, egg, ink]"],
    )
    assert config.participants == 20
    assert config.completion["code"] == "ABC123"
    assert config.words == ("cat", "dog", "sun", "egg", "ink")


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("kind=survey", "kind must be one of turing, readability"),
        ("words=[cat, 'two words']", "'two words' is not a word"),
        ("words=[cat, cat]", "'cat' is listed twice"),
        ("participants=0", "participants must be an integer from 1 to 10000"),
        ("human_writers=3", r"human_writers \(3\) must be at least foils \(4\)"),
        ("equivalence_margin=1.5", "equivalence_margin must be a number in"),
        ("colour=red", "unknown key 'colour'"),
        ("capture.on_lift=ignore", "capture.on_lift must be one of restart, flag"),
        ("delayed_strokes=maybe", r"delayed_strokes must be true \(.*\) or false \(one stroke\)"),
        ("delayed_strokes=1", "delayed_strokes must be true"),
        ("delayed_strokes=null", "delayed_strokes must be true"),
        ("capture.delayed_max_size=0", r"capture.delayed_max_size must be a number in \(0, 1\]"),
        ("capture.delayed_max_size=1.5", r"capture.delayed_max_size must be a number in \(0, 1\]"),
        ("capture.delayed_max_size=true", "capture.delayed_max_size must be a number"),
        (
            "robot.write_overrides=[delayed_strokes=false]",
            "robot.write_overrides: 'delayed_strokes=false': set the study's top-level",
        ),
        (
            "attention_checks=[{after_trial: 99, instruction: x, expect: {choose_sample: 1}}]",
            r"attention_checks\[0\].after_trial must be between 0 and 10",
        ),
        (
            "attention_checks=[{after_trial: 1, instruction: x, expect: {choose_sample: 6}}]",
            "choose_sample: K}: the sample numbered K on screen, K in 1..5",
        ),
        (
            "attention_checks=[{after_trial: 1, instruction: x, expect: {typed_text: a}}]",
            "unknown key 'typed_text'",
        ),
        ("name=../up", "name must be 1-64 letters, digits"),
        ("words", "must look like key=value"),
    ],
)
def test_bad_settings_name_the_key_and_what_is_accepted(override, message):
    with pytest.raises(UsageError, match=message) as err:
        load_study(REPO / "conf/study/turing.yaml", [override])
    assert str(err.value).startswith(str(REPO / "conf/study/turing.yaml"))
    assert "\n" not in str(err.value)


def test_readability_needs_an_even_number_of_words():
    with pytest.raises(UsageError, match="even number of words"):
        readability(words=WORDS[:5])


def test_unreadable_study_files_are_named(tmp_path):
    with pytest.raises(UsageError, match="no such study file"):
        load_study(tmp_path / "nope.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: [unclosed\n")
    with pytest.raises(UsageError, match=r"bad.yaml: not valid YAML at line \d"):
        load_study(bad)
    bad.write_text("- a list\n")
    with pytest.raises(UsageError, match="must hold a mapping"):
        load_study(bad)
