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
from dataclasses import dataclass, field

import numpy as np

from prg.alphabet import text_to_labels, unsupported_chars
from prg.checks import GENERATE_RANGES, check_text_length
from prg.errors import SettingsError, UsageError
from prg.fields import check_ranges
from prg.pipeline.connect import ConnectionSettings, connect_sequence
from prg.pipeline.dmp import basis_count, fit_dmp, rollout
from prg.pipeline.layout import LayoutSettings, layout_letters, word_breaks
from prg.pipeline.marks import MarkSettings, crossed_exit, letter_marks
from prg.pipeline.timing import stroke_duration, timed_body
from prg.pipeline.word import DEFAULT_SPEED_CM_S, WordTrajectory, assemble_word

log = logging.getLogger(__name__)

CONNECTION_METHODS = ("hand", "alg1", "straight")
TIMINGS = ("human", "constant")
DECODING_MODES = ("hand", "posterior")


@dataclass(frozen=True)
class GenerateSettings:
    """How a word is generated and timed (all config values, ``conf/write.yaml``).

    Attributes
    ----------
    mode
        ``"hand"`` (default): each letter is drawn from the posterior of a real writer's
        letter of its class, one writer's letters for the whole word (the writer chosen by
        ``seed``, or matched to a person's letters: ``Writer(style=...)``), its std scaled by
        ``hand_temperature`` (:mod:`prg.pipeline.hands`); the letters vary as writers' do and
        stay legible. ``"posterior"``: the paper's decoding of the command's posterior
        (``temperature``, ``impute_steps``).
    hand_temperature
        the std scale of a hand's letter posteriors (0: the letters' means).
    seed
        chooses the samples and, unless ``hand_seed`` is given, the writer: one seed one
        word, another seed another hand.
    hand_seed
        chooses the writer alone (None: ``seed``): the same ``hand_seed`` with other
        ``seed`` values writes a word again in the same hand, as a person writes it twice.
    temperature
        posterior mode: 0 decodes each letter's posterior mean (the paper); > 0 draws
        latents with their std scaled by it, reproducibly for ``seed``.
    impute_steps
        rounds of imputing the modalities a letter was not given before decoding
        (:meth:`prg.models.muse.MUSE.encode_imputed`; families without a joint posterior ignore
        it). 0 is the paper's decoding. The demo MUSE's letters from labels read right (folded
        coherence, whole test split) 0.68 with 0 rounds, 0.89 with 10, 0.94 with 20.
    method
        ``"hand"`` (default: the paper's Algorithm 1 unless its stroke cuts through a
        letter, then a smooth stroke that keeps off the ink, :mod:`prg.pipeline.joins`),
        ``"alg1"`` (the paper's connection algorithm) or ``"straight"``.
    timing
        ``"human"`` (default): the pen slows in curves (the speed-curvature power law,
        beta 1/3) and some strokes go faster than others (``speed_variation``, seeded by
        ``seed``) (:func:`prg.pipeline.timing.human_samples`); ``"constant"``: the paper's
        constant speed between ramps. Both take ``length / speed_cm_s`` seconds.
    speed_variation
        strength of the stroke-to-stroke speed variation (0: none).
    speed_cm_s
        mean pen speed over the word.
    ramp_s
        start/stop ramp duration.
    samples_per_s
        DMP demonstration samples per second of writing.
    basis_per_100_samples
        DMP basis functions per 100 demonstration samples. Words from the
        decoder carry more detail than smooth test curves (corners where letters join): with
        70 per 100 samples at 100 samples/s, 30 random words of 6-12 letters from the demo MUSE
        were reproduced with RMSE median 0.024 mm, 90th percentile 0.061 mm, worst 0.107 mm
        (50: 0.058 / 0.123 / 0.261; 20 left up to 0.3 mm; ``benchmarks/bench_write.py``).
    delayed_strokes
        after the cursive body, dot the i's and j's and cross the t's and f's
        (``marks``: which letters, sizes; :mod:`prg.pipeline.marks`). False: the paper's single
        stroke.
    """

    mode: str = "hand"
    hand_temperature: float = 0.5
    temperature: float = 0.0
    seed: int = 0
    hand_seed: int | None = None
    impute_steps: int = 20
    method: str = "hand"
    timing: str = "human"
    speed_variation: float = 0.15
    speed_cm_s: float = DEFAULT_SPEED_CM_S
    ramp_s: float = 0.3
    samples_per_s: float = 100.0
    basis_per_100_samples: int = 70
    delayed_strokes: bool = True
    marks: MarkSettings = field(default_factory=MarkSettings)
    layout: LayoutSettings = field(default_factory=LayoutSettings)
    connection: ConnectionSettings = field(default_factory=ConnectionSettings)

    def __post_init__(self) -> None:
        check_ranges(self, GENERATE_RANGES)
        if self.mode not in DECODING_MODES:
            raise SettingsError("mode", f"{self.mode!r}: choose hand or posterior")
        if self.timing not in TIMINGS:
            raise SettingsError("timing", f"{self.timing!r}: choose human or constant")
        if self.method not in CONNECTION_METHODS:
            raise SettingsError("method", f"{self.method!r}: choose hand, alg1 or straight")
        if not isinstance(self.delayed_strokes, bool):
            raise SettingsError(
                "delayed_strokes", f"{self.delayed_strokes!r}: choose true or false"
            )


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
    if params.delayed_strokes:  # the bar is its own stroke: a crossed letter ends at its foot
        chars = [c for c in text if c != " "]
        placed = [
            crossed_exit(p) if params.marks.mark_of(c) == "bar" else p
            for c, p in zip(chars, placed)
        ]
    connections = connect_sequence(
        placed, params.connection, method=params.method, breaks=word_breaks(text)
    )
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
