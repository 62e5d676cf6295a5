"""Tests of ``prg.alphabet``."""

import pytest

from prg.alphabet import (
    ALPHABET,
    NUM_CLASSES,
    char_to_label,
    label_to_char,
    labels_to_text,
    text_to_labels,
)
from prg.errors import UsageError


def test_class_ids_follow_digits_upper_lower():
    assert NUM_CLASSES == 62
    assert [char_to_label(c) for c in "09AZaz"] == [0, 9, 10, 35, 36, 61]
    assert ALPHABET[char_to_label("q")] == "q"


def test_text_round_trip():
    text = "Hello42world"
    assert labels_to_text(text_to_labels(text)) == text


def test_unsupported_characters_are_all_named():
    with pytest.raises(UsageError, match=r"'ñ'.*'!'|'!'.*'ñ'"):
        text_to_labels("añb!")


def test_single_char_error_names_it():
    with pytest.raises(UsageError, match="'-'"):
        char_to_label("-")


@pytest.mark.parametrize("bad", [-1, 62, 3.5, "a"])
def test_label_out_of_range(bad):
    with pytest.raises(UsageError, match=r"0\.\.61"):
        label_to_char(bad)
