"""Helpers shared by the tests that were split out of tests/test_study_design.py."""

from __future__ import annotations

from pathlib import Path

from studies.design import (
    study_from_dict,
)

REPO = Path(__file__).resolve().parents[2]


WORDS = ["bell", "cat", "jump", "dog", "house", "water", "light", "moon", "green", "paper"]


def turing(**overrides):
    doc = {"name": "t", "kind": "turing", "words": WORDS, "participants": 50, "seed": 7}
    return study_from_dict({**doc, **overrides})


def readability(**overrides):
    doc = {"name": "r", "kind": "readability", "words": WORDS, "participants": 30, "seed": 7}
    return study_from_dict({**doc, **overrides})
