"""Generate: decoded letters -> laid-out word -> connection strokes -> one DMP (NumPy only).

:func:`compose_word` applies the final processing map (``prg.pipeline.layout``: sizes and
baseline; ``prg.pipeline.connect``: connection strokes) to the decoded letters, adds the delayed
strokes (``prg.pipeline.marks``: i/j dots, t/f bars), times the path from rest to rest
(``prg.pipeline.timing``) and fits one DMP to the cursive body (``prg.pipeline.dmp``); the
delayed strokes are timed as straight minimum-jerk strokes after it. :func:`clean_text` makes a
user's text ready to write.
"""

from __future__ import annotations

import logging

import numpy as np

from prg.alphabet import text_to_labels, unsupported_chars
from prg.checks import check_text_length
from prg.errors import UsageError
from prg.pipeline.connect import connect_sequence
from prg.pipeline.dmp import basis_count, fit_dmp, rollout
from prg.pipeline.joins import CLOSED_AT_TOP, closed_exit
from prg.pipeline.layout import layout_letters, word_breaks
from prg.pipeline.marks import crossed_exit, letter_marks
from prg.pipeline.settings import (  # noqa: F401 (exported here too)
    CONNECTION_METHODS,
    DECODING_MODES,
    TIMINGS,
    GenerateSettings,
)
from prg.pipeline.timing import stroke_duration, timed_body
from prg.pipeline.word import WordTrajectory, assemble_word

log = logging.getLogger(__name__)


def compose_word(
    letters: np.ndarray, text: str, params: GenerateSettings | None = None
) -> tuple[WordTrajectory, np.ndarray]:
    """The final processing map and the DMP on decoded letters (the second half of
    :meth:`prg.writer.Writer.generate`).

    Parameters
    ----------
    letters : ndarray, shape (N, k, 2)
        Normalised letter trajectories (y up), one per non-space character of ``text``.
    text : str
    params : GenerateSettings, optional

    Returns
    -------
    word : WordTrajectory
        Points, segments (the delayed strokes last), text, timing and the DMP fitted to the
        body (``word.dmp``).
    rollout : ndarray, shape (n, 2)
        The DMP's rollout on the demonstration's time grid (the body).
    """
    params = params or GenerateSettings()
    placed = layout_letters(list(letters), text, params.layout)
    chars = [c for c in text if c != " "]
    breaks = word_breaks(text)
    if params.delayed_strokes:  # the bar is its own stroke: a crossed letter ends at its foot
        placed = [
            crossed_exit(p) if params.marks.mark_of(c) == "bar" else p
            for c, p in zip(chars, placed)
        ]
    if params.method == "hand":  # joined as a writer joins: an o is left where it closes
        joined = [not b for b in breaks] + [False]  # the word's last letter joins nothing
        placed = [
            closed_exit(p) if c in CLOSED_AT_TOP and to_next else p
            for c, p, to_next in zip(chars, placed, joined)
        ]
    connections = connect_sequence(placed, params.connection, method=params.method, breaks=breaks)
    marks = (
        letter_marks(placed, text, params.marks, params.layout) if params.delayed_strokes else []
    )
    word = assemble_word(
        placed, connections, text, speed_cm_s=params.speed_cm_s, marks=[m for *_, m in marks]
    )
    samples, duration = timed_body(word.points[: word.body_end], params)
    n_basis = basis_count(len(samples), per_100_points=params.basis_per_100_samples)
    dmp = fit_dmp(samples, tau=duration, n_basis=n_basis, velocities="rest")  # a pen at rest
    word.dmp = dmp
    word.duration_s = duration + sum(
        stroke_duration(path, params.speed_cm_s) for _, path in word.delayed_strokes()
    )
    # integrated on the demonstration's own grid (1.4 samples per basis function): at most 5 um
    # from a fine integration on five words, under the fit's own error (0.003 mm RMS, 0.04 mm
    # at worst), at 0.4-0.6 of the default's cost (three times the samples)
    return word, rollout(dmp, samples_per_basis=1)


def clean_text(text: str, on_unknown: str = "error", key: str = "text") -> str:
    """``text`` ready to write: words separated by single spaces, unsupported characters handled.

    Parameters
    ----------
    text : str
    on_unknown : {"error", "skip"}
        ``"error"``: one error listing every character outside 0-9, A-Z, a-z (spaces aside);
        ``"skip"``: drop them (logged) and write the rest.
    key : str
        The option the text came from, for the message when it is longer than
        :data:`prg.checks.MAX_TEXT_LETTERS` letters.

    Raises
    ------
    UsageError
        For an unsupported character with ``on_unknown="error"``, an unknown ``on_unknown``, or
        nothing left to write.
    """
    if on_unknown not in ("error", "skip"):
        raise UsageError(f"on_unknown {on_unknown!r}: choose error or skip")
    words = text.split()
    unknown = unsupported_chars("".join(words))
    if unknown and on_unknown == "error":
        text_to_labels("".join(words))  # raises, listing them
    if unknown:
        log.warning("skipping unsupported characters %s", ", ".join(map(repr, unknown)))
        words = ["".join(c for c in w if c not in unknown) for w in words]
    cleaned = " ".join(w for w in words if w)
    if not cleaned:
        raise UsageError(f"text {text!r} has no letters to write: accepted are 0-9, A-Z and a-z")
    return check_text_length(cleaned, key)
