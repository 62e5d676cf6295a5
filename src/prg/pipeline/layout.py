"""Sizing and placement of decoded letters: steps 1-3 of the paper's final processing map.

The paper (section "Generate" of the Robotic Dictaphone) homogenises the decoded letters before
connecting them:

1. scale every letter to its expected proportion in the word (a lowercase ``a`` is half as tall
   as an uppercase ``A``);
2. translate it vertically so that it sits on the baseline, except ``f g j p q y``, which begin at
   a lower, predefined coordinate (descenders);
3. place consecutive letters a fixed horizontal distance apart.

Letters arrive as the models decode them: 100 points, normalised by
:func:`prg.data.preprocess.normalise` (centred on the mean point, largest absolute coordinate 1,
**y up**). They leave in centimetres, left to right, the baseline at ``y = 0``.

Height classes (``H`` = ``LayoutSettings.letter_height``):

* **full**: uppercase, digits and the ascenders ``b d f h k l t``: bounding box from ``0`` to
  ``H``;
* **x-height**: the other lowercase letters, ``0`` to ``x_height * H``;
* **descender**: ``g j p q y``: ``-descender * H`` to ``x_height * H`` (the body on the baseline
  band, the tail below it);
* ``f`` is in both of the paper's lists (ascender and descender). We follow the paper literally:
  ``f`` spans ``-descender * H`` to ``H``, the looped cursive ``f`` of the UJI writers and the
  synthetic script fonts. A print ``f`` without a tail would be stretched down; put ``f`` in
  ``LayoutSettings.descenders`` or not to choose.

Each letter is scaled uniformly (aspect ratio kept) so that its bounding-box height is its class
height, unless that would make it wider than ``max_width * H``; then it is scaled to that width
(and is shorter than its class, still standing on its class's bottom line). A letter with no
height (a horizontal stroke) is scaled by the width guard alone.

Horizontally, letter ``k + 1``'s bounding box starts ``gap`` after letter ``k``'s ends; each space
in the text adds ``space_width`` (several words on one line). Leading and trailing spaces are
ignored. Boxes of consecutive letters never overlap.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from prg.alphabet import unsupported_chars
from prg.errors import UsageError
from prg.pipeline.settings import LayoutSettings  # exported here too

_EPS = 1e-9


def letter_band(char: str, params: LayoutSettings | None = None) -> tuple[float, float]:
    """Bottom and top (cm, baseline at 0) of a character's bounding box.

    Parameters
    ----------
    char : str
        One supported character (0-9, A-Z, a-z).
    params : LayoutSettings, optional

    Returns
    -------
    (bottom, top) : tuple of float
    """
    p = params or LayoutSettings()
    if len(char) != 1 or unsupported_chars(char):
        raise UsageError(f"unsupported character {char!r}: accepted are 0-9, A-Z and a-z")
    full = not char.islower() or char in p.ascenders
    top = p.letter_height if full else p.x_height * p.letter_height
    bottom = -p.descender * p.letter_height if char in p.descenders else 0.0
    return bottom, top


def place_letter(
    points, char: str, left: float, params: LayoutSettings | None = None
) -> np.ndarray:
    """Scale one normalised letter to its band and put its box's left edge at ``left``.

    Parameters
    ----------
    points : ndarray, shape (n, 2)
        The letter, any scale, y up.
    char : str
        Its character (decides the band, :func:`letter_band`).
    left : float
        x of the left edge of its bounding box, cm.
    params : LayoutSettings, optional

    Returns
    -------
    ndarray, shape (n, 2)
        In centimetres: bounding box ``[left, left + w] x [bottom, bottom + h]`` with ``h`` the
        band height (or less, under the width guard).
    """
    p = params or LayoutSettings()
    arr = np.asarray(points, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] < 1:
        raise UsageError(f"letter {char!r} must have shape (n, 2), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise UsageError(f"letter {char!r} contains NaN or infinite values")
    bottom, top = letter_band(char, p)
    lo, hi = arr.min(axis=0), arr.max(axis=0)
    width, height = hi - lo
    scale = np.inf
    if height > _EPS:
        scale = (top - bottom) / height
    if width > _EPS:
        scale = min(scale, p.max_width * p.letter_height / width)
    if not np.isfinite(scale):
        raise UsageError(f"letter {char!r} has zero extent; cannot size it")
    return (arr - lo) * scale + np.array([left, bottom])


def layout_letters(
    letters: Sequence[np.ndarray], text: str, params: LayoutSettings | None = None
) -> list[np.ndarray]:
    """Size and place the letters of ``text`` left to right on the baseline ``y = 0``.

    Parameters
    ----------
    letters : sequence of ndarray, each shape (n_i, 2)
        One normalised trajectory (y up) per non-space character of ``text``, in order.
    text : str
        The characters (0-9, A-Z, a-z) and spaces between words.
    params : LayoutSettings, optional

    Returns
    -------
    list of ndarray, each shape (n_i, 2)
        The letters in centimetres; the first box starts at ``x = 0``.

    Raises
    ------
    UsageError
        An unsupported character, or a number of letters different from the characters'.
    """
    p = params or LayoutSettings()
    bad = [c for c in unsupported_chars(text) if c != " "]
    if bad:
        shown = ", ".join(repr(c) for c in bad)
        raise UsageError(
            f"text {text!r} has unsupported characters {shown}: accepted are 0-9, A-Z, a-z and spaces"
        )
    chars = [c for c in text if c != " "]
    if len(chars) != len(letters):
        raise UsageError(
            f"text {text!r} has {len(chars)} characters but {len(letters)} letter trajectories "
            "were given"
        )
    out: list[np.ndarray] = []
    cursor = 0.0
    spaces = 0
    k = 0
    for c in text.strip(" "):
        if c == " ":
            spaces += 1
            continue
        if out:
            cursor += p.gap + spaces * p.space_width
        spaces = 0
        placed = place_letter(letters[k], c, cursor, p)
        out.append(placed)
        cursor = float(placed[:, 0].max())
        k += 1
    return out


def word_breaks(text: str) -> list[bool]:
    """For each pair of consecutive letters of ``text``, True when a space separates them.

    Returns
    -------
    list of bool, length (number of non-space characters - 1)
    """
    out = []
    seen_letter = False
    pending = False
    for c in text:
        if c == " ":
            pending = seen_letter
            continue
        if seen_letter:
            out.append(pending)
        seen_letter, pending = True, False
    return out
