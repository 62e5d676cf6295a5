"""The 62-class alphabet of the Robotic Dictaphone: digits, upper- and lowercase letters.

Class ids: ``0-9`` -> 0..9, ``A-Z`` -> 10..35, ``a-z`` -> 36..61.
"""

from __future__ import annotations

import string
from collections.abc import Iterable, Sequence

import numpy as np

from prg.errors import UsageError

ALPHABET: str = string.digits + string.ascii_uppercase + string.ascii_lowercase
NUM_CLASSES: int = len(ALPHABET)
_INDEX: dict[str, int] = {ch: i for i, ch in enumerate(ALPHABET)}


def is_supported(char: str) -> bool:
    """True if ``char`` is one of the 62 supported characters."""
    return char in _INDEX


def char_to_label(char: str) -> int:
    """Class id of one character.

    Raises
    ------
    UsageError
        If ``char`` is not a single character among 0-9, A-Z, a-z.
    """
    try:
        return _INDEX[char]
    except (KeyError, TypeError):
        raise UsageError(
            f"unsupported character {char!r}: accepted are 0-9, A-Z and a-z (62 classes)"
        ) from None


def label_to_char(label: int) -> str:
    """Character of a class id in ``0..61``."""
    if not isinstance(label, int | np.integer) or not 0 <= int(label) < NUM_CLASSES:
        raise UsageError(
            f"label {label!r} is out of range: accepted are integers 0..{NUM_CLASSES - 1}"
        )
    return ALPHABET[int(label)]


def text_to_labels(text: str) -> list[int]:
    """Class ids of every character of ``text``.

    Raises
    ------
    UsageError
        Listing every unsupported character of ``text`` at once.
    """
    unknown = unsupported_chars(text)
    if unknown:
        shown = ", ".join(repr(c) for c in unknown)
        raise UsageError(
            f"text {text!r} has unsupported characters {shown}: accepted are 0-9, A-Z and a-z"
        )
    return [_INDEX[c] for c in text]


def labels_to_text(labels: Iterable[int]) -> str:
    """Inverse of :func:`text_to_labels`."""
    return "".join(label_to_char(int(label)) for label in labels)


def unsupported_chars(text: Sequence[str]) -> list[str]:
    """Distinct characters of ``text`` outside the alphabet, in order of first appearance."""
    return list(dict.fromkeys(c for c in text if c not in _INDEX))
