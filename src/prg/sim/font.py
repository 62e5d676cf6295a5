"""Words without a trained model: Hershey single-line font letters, composed like ``prg-write``.

:func:`font_word` gives the simulator (its tests, its benchmark, a first try on a machine without
``models/``) a realistic word trajectory: each letter is a glyph of a single-line Hershey font
joined into one stroke (for a letter that gets a delayed stroke, :mod:`prg.pipeline.marks`, only
the glyph's longest stroke: the dot or bar is the delayed stroke's) and normalised the way the
training data are
(:func:`prg.data.synthetic.join_strokes`, :func:`prg.data.preprocess.preprocess_stroke`), then
laid out, connected (Algorithm 1) and fitted with one DMP by
:func:`prg.pipeline.compose.compose_word` — the same final processing map ``prg-write`` uses
on a model's decoded letters.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from prg.data.preprocess import preprocess_stroke
from prg.data.synthetic import join_strokes
from prg.errors import UsageError
from prg.pipeline.word import WordTrajectory

if TYPE_CHECKING:
    from prg.pipeline.compose import GenerateSettings

__all__ = ["font_word"]


def font_word(
    text: str, font: str = "futural", params: GenerateSettings | None = None
) -> WordTrajectory:
    """A word (or words separated by spaces) written in a Hershey font, with its DMP.

    Parameters
    ----------
    text : str
        Letters 0-9, A-Z, a-z, and spaces.
    font : str
        A Hershey font name (``futural``, ``rowmans``, ``scripts``, ``cursive`` ...).
    params : GenerateSettings, optional
        Layout, connection and DMP settings (``prg-write``'s defaults).

    Returns
    -------
    WordTrajectory
        With ``dmp`` set.
    """
    from HersheyFonts import HersheyFonts

    from prg.pipeline.compose import clean_text, compose_word

    text = clean_text(text)
    typeface = HersheyFonts()
    try:
        typeface.load_default_font(font)
    except Exception:
        raise UsageError(f"font {font!r}: not a Hershey font name (e.g. futural)") from None
    from prg.pipeline.compose import GenerateSettings

    params = params or GenerateSettings()
    letters = []
    for char in text.replace(" ", ""):
        strokes = [np.asarray(s, dtype=np.float64) for s in typeface.strokes_for_text(char)]
        strokes = [s for s in strokes if len(s) > 1]
        if params.delayed_strokes and params.marks.mark_of(char):
            # the glyph's own dot or bar gives way to the delayed stroke: keep its main stroke
            strokes = [max(strokes, key=lambda s: np.linalg.norm(np.diff(s, axis=0), axis=1).sum())]
        letters.append(preprocess_stroke(join_strokes(strokes)))
    word, _ = compose_word(np.stack(letters), text, params)
    return word
