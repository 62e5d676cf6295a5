"""Tests of ``studies.overrides``: ``key=value`` overrides of a study file (``prg-study build
--set``)."""

from __future__ import annotations

import pytest

from prg.errors import UsageError
from studies.overrides import apply_overrides, parse_override


def test_a_dotted_key_reaches_into_sections_and_values_are_yaml():
    doc = {"name": "pilot", "page": {"title": "Old"}, "words": ["cat"]}
    out = apply_overrides(
        doc, ["page.title=A new title", "words=[bell, jump]", "analysis.alpha=0.01", "seed="]
    )
    assert out == {
        "name": "pilot",
        "page": {"title": "A new title"},
        "words": ["bell", "jump"],
        "analysis": {"alpha": 0.01},
        "seed": None,
    }
    assert doc == {"name": "pilot", "page": {"title": "Old"}, "words": ["cat"]}  # a copy


def test_later_overrides_win():
    assert apply_overrides({}, ["foils=3", "foils=4"]) == {"foils": 4}


def test_parse_override_splits_the_key_and_strips_spaces():
    assert parse_override(" page . title = x") == (["page", "title"], "x")


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("foils", "must look like key=value"),
        ("page..title=x", "must look like key=value"),
        ("=3", "must look like key=value"),
        ("words=[cat", "the value is not valid YAML"),
        ("name.first=x", "'name' is not a section"),
    ],
)
def test_a_malformed_override_is_named_in_one_line(override, message):
    with pytest.raises(UsageError) as err:
        apply_overrides({"name": "pilot"}, [override])
    assert message in str(err.value) and repr(override) in str(err.value)
    assert "\n" not in str(err.value)
