"""The settings of writing a word: :class:`GenerateSettings` and its :class:`MarkSettings`.

Each numeric field declares the values it accepts (:func:`prg.fields.ranged`): the dataclass
checks them (:func:`prg.fields.check_fields`) and :data:`prg.checks.RANGES` takes its
``generate.*`` and ``marks.*`` entries from them. This module imports no numpy (nor the pipeline
modules that do), so that every command checks its config before loading them;
:mod:`prg.pipeline.compose` and :mod:`prg.pipeline.marks`, which use these settings, export them
too.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from prg.checks import SEED, SEED_MAX, TEMPERATURE, count, non_negative, positive
from prg.errors import SettingsError
from prg.fields import check_fields, ranged

if TYPE_CHECKING:
    from prg.pipeline.connect import ConnectionSettings
    from prg.pipeline.layout import LayoutSettings

__all__ = [
    "CONNECTION_METHODS",
    "DECODING_MODES",
    "DEFAULT_SPEED_CM_S",
    "TIMINGS",
    "GenerateSettings",
    "MarkSettings",
]

CONNECTION_METHODS = ("hand", "alg1", "straight")
TIMINGS = ("human", "constant")
DECODING_MODES = ("hand", "posterior")
DEFAULT_SPEED_CM_S = 2.0


def _layout() -> LayoutSettings:
    from prg.pipeline.layout import LayoutSettings

    return LayoutSettings()


def _connection() -> ConnectionSettings:
    from prg.pipeline.connect import ConnectionSettings

    return ConnectionSettings()


@dataclass(frozen=True)
class MarkSettings:
    """Which letters get a delayed stroke and its size (fractions of the letter height ``H``).

    Attributes
    ----------
    dotted
        letters that get a dot above the stem (``"ij"``).
    crossed
        letters that get a bar across the stem (``"tf"``).
    dot_gap
        space between the stem's top and the dot (0.2 H: 0.4 of the x-height).
    dot_radius
        the dot's radius (0.015 H: 0.22 mm for a 1.5 cm letter; a circle that small
        under a 0.4 mm pen inks a filled dot, not a ring).
    bar_width
        length of a bar (0.4 H).
    bar_height
        height of a bar as a fraction of the x-height (1.0: on the x-height line).
    """

    dotted: str = "ij"
    crossed: str = "tf"
    dot_gap: float = ranged(0.2, positive(0.6))  # 0: the dot on the stem; more floats away
    dot_radius: float = ranged(0.015, positive(1))
    bar_width: float = ranged(0.4, positive(3))
    bar_height: float = ranged(1.0, positive(3))

    def __post_init__(self) -> None:
        from prg.alphabet import unsupported_chars  # numpy: imported when a value is checked

        check_fields(self)
        for name in ("dotted", "crossed"):
            value = getattr(self, name)
            if not isinstance(value, str) or unsupported_chars(value) or " " in value:
                raise SettingsError(name, f"{value!r}: give letters from 0-9, A-Z, a-z")
        both = sorted(set(self.dotted) & set(self.crossed))
        if both:
            raise SettingsError("crossed", f"{both[0]!r} is also dotted: one mark per letter")

    def mark_of(self, char: str) -> str | None:
        """``"dot"``, ``"bar"`` or None for a character."""
        if char in self.dotted:
            return "dot"
        if char in self.crossed:
            return "bar"
        return None


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
    hand_temperature: float = ranged(0.5, TEMPERATURE)
    temperature: float = ranged(0.0, TEMPERATURE)
    seed: int = ranged(0, SEED)
    hand_seed: int | None = ranged(None, count(0, SEED_MAX, optional=True))
    impute_steps: int = ranged(20, count(0, 1000))
    method: str = "hand"
    timing: str = "human"
    speed_variation: float = ranged(0.15, non_negative(2))
    speed_cm_s: float = ranged(DEFAULT_SPEED_CM_S, positive(1000))
    ramp_s: float = ranged(0.3, non_negative(60))
    samples_per_s: float = ranged(100.0, positive(10_000))
    basis_per_100_samples: int = ranged(70, count(1, 100))
    delayed_strokes: bool = True
    marks: MarkSettings = field(default_factory=MarkSettings)
    layout: LayoutSettings = field(default_factory=_layout)
    connection: ConnectionSettings = field(default_factory=_connection)

    def __post_init__(self) -> None:
        check_fields(self)
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
