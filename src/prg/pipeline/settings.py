"""The settings of writing a word: :class:`GenerateSettings` and its :class:`MarkSettings`,
:class:`LayoutSettings` and :class:`ConnectionSettings`.

Each numeric field declares the values it accepts (:func:`prg.fields.ranged`): the dataclass
checks them (:func:`prg.fields.check_fields`) and :data:`prg.checks.RANGES` takes its
``generate.*``, ``marks.*``, ``layout.*`` and ``connection.*`` entries from them. One field is
not declared: ``ConnectionSettings.alpha_max`` is in radians while the config gives
``connection.alpha_max_deg`` in degrees, so that option keeps its entry in
:data:`prg.checks.TABLE` (:data:`prg.checks.ALPHA_MAX_DEG`) and the field is checked against the
same range, converted. This module imports no numpy (nor the pipeline modules that do), so that
every command checks its config before loading them; :mod:`prg.pipeline.compose`,
:mod:`prg.pipeline.marks`, :mod:`prg.pipeline.layout` and :mod:`prg.pipeline.connect`, which use
these settings, export them too.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any, Literal

from prg.checks import (
    ALPHA_MAX_DEG,
    SEED,
    SEED_MAX,
    TEMPERATURE,
    WEIGHT_MAX,
    count,
    non_negative,
    positive,
)
from prg.errors import SettingsError
from prg.fields import as_float, check_fields, checked, ranged

__all__ = [
    "CONNECTION_METHODS",
    "DECODING_MODES",
    "DEFAULT_SPEED_CM_S",
    "JOIN_MODES",
    "TIMINGS",
    "ConnectionSettings",
    "GenerateSettings",
    "JoinMode",
    "LayoutSettings",
    "MarkSettings",
]

CONNECTION_METHODS = ("hand", "alg1", "straight")
TIMINGS = ("human", "constant")
DECODING_MODES = ("hand", "posterior")
DEFAULT_SPEED_CM_S = 2.0
JoinMode = Literal["first", "retrace"]
JOIN_MODES = ("first", "retrace")
LAYOUT_SIZE = positive(100)  # cm, or fractions of the letter height


@dataclass(frozen=True)
class LayoutSettings:
    """Sizes of the word layout, in centimetres (ratios relative to ``letter_height``)
    (:mod:`prg.pipeline.layout`).

    Attributes
    ----------
    letter_height : float
        Height ``H`` of uppercase letters, digits and ascenders (1.5 cm: a robot pen's
        comfortable size; the x-height is then 0.75 cm).
    x_height : float
        Height of x-height letters as a fraction of ``H`` (0.5: the paper's "half-height").
    descender : float
        Depth below the baseline of descender tails, as a fraction of ``H`` (0.45).
    max_width : float
        Widest a letter may be, as a fraction of ``H`` (1.6: wide enough for ``m``, ``w``, ``W``;
        guards against a flat decoded letter being blown up).
    gap : float
        Horizontal distance between consecutive letters' bounding boxes (0.2 cm).
    space_width : float
        Extra horizontal distance per space between words (0.6 cm).
    ascenders : str
        Lowercase letters of full height.
    descenders : str
        Letters whose tail goes below the baseline.

    Every size is a finite number in (0, 100], the range of the config's ``layout.*``; a refused
    value raises :class:`~prg.errors.SettingsError` naming its field (``gap must be a finite
    number in (0, 100], got 0``).
    """

    letter_height: float = ranged(1.5, LAYOUT_SIZE)
    x_height: float = ranged(0.5, LAYOUT_SIZE)
    descender: float = ranged(0.45, LAYOUT_SIZE)
    max_width: float = ranged(1.6, LAYOUT_SIZE)
    gap: float = ranged(0.2, LAYOUT_SIZE)
    space_width: float = ranged(0.6, LAYOUT_SIZE)
    ascenders: str = "bdfhklt"
    descenders: str = "fgjpqy"

    def __post_init__(self) -> None:
        check_fields(self)


def _alpha_max(value: Any, name: str) -> float:
    """``value`` (radians) as a float when its degrees lie in :data:`prg.checks.ALPHA_MAX_DEG`,
    the range of the config's ``connection.alpha_max_deg``."""
    x = as_float(value, name)
    if not (math.isfinite(x) and ALPHA_MAX_DEG.accepts(math.degrees(x))):
        raise SettingsError(name, f"must be in (0, pi] radians, got {value!r}")
    return x


_FLOATS = ("delta", "theta_o", "theta_a", "theta_f", "theta_p", "home_radius")


@dataclass(frozen=True)
class ConnectionSettings:
    """Parameters of :func:`prg.pipeline.connect.connect_letters` as the config gives them
    (lengths in centimetres, angles in radians).

    Defaults are tuned for letters 0.75 cm (x-height) to 1.5 cm (full height) tall, laid out by
    :mod:`prg.pipeline.layout` with its default gap.

    Attributes
    ----------
    delta : float
        Step length of the connection and the largest gap it leaves (0.05 cm, about the spacing of
        the 100 points of a decoded letter at this size).
    alpha_max : float
        Largest heading change per step (18 degrees): a turning radius of
        ``delta / (2 sin(alpha_max / 2)) = 0.16 cm``, a pen-like curvature at this letter size.
    theta_o : float
        Weight of the index term ``j / m`` (prefers the next letter's early points).
    theta_a : float
        Weight of the normalised turn (prefers going straight on: smooth exits).
    theta_f : float
        Weight of the normalised distance to the next letter's first point (pulls to its start).
    theta_p : float
        Weight of the normalised distance to the candidate's own target point (pulls towards the
        nearest part of the next letter).
    home_radius : float
        Distance to the next letter's first point below which the pen aims at that point alone
        (0.4 cm, 2.5 turning radii; :mod:`prg.pipeline.connect`); 0: no homing (the paper's
        unmodified candidate competition).
    max_steps : int
        Cap on steered steps before the straight fallback (400 steps = 20 cm of path); 0: the
        straight joiner.
    join : {"first", "retrace"}
        How the connection enters the next letter (:mod:`prg.pipeline.connect`).

    The weights were chosen on the synthetic test split (300 random lowercase pairs) and by eye
    on rendered words: the distance-to-start term dominates (``theta_f = 4``), which gives short,
    rounded joins (median path 1.03 times the straight distance; the p90 of the total turning of
    a connection is about 190 degrees, i.e. at most a hook or a loop). Smaller ``theta_f`` or
    larger ``theta_a`` make wider detours (``theta_f = 1``: p90 path 3.4 times the distance).

    The settings accept what the config accepts (``connection.*`` of :data:`prg.checks.RANGES`,
    taken from these fields; ``alpha_max`` in (0, pi] radians, the config's ``alpha_max_deg`` in
    (0, 180]); a refused value raises :class:`~prg.errors.SettingsError` naming its field.
    :func:`~prg.pipeline.connect.connect_letters` checks its arguments with this class, so the
    function, the settings and the command accept the same values. The lengths and weights are
    stored as ``float``.
    """

    delta: float = ranged(0.05, positive(10))
    alpha_max: float = checked(math.radians(18.0), _alpha_max)
    theta_o: float = ranged(1.0, non_negative(WEIGHT_MAX))
    theta_a: float = ranged(1.0, non_negative(WEIGHT_MAX))
    theta_f: float = ranged(4.0, non_negative(WEIGHT_MAX))
    theta_p: float = ranged(0.5, non_negative(WEIGHT_MAX))
    home_radius: float = ranged(0.4, non_negative(100))
    max_steps: int = ranged(400, count(0, 100_000))
    join: JoinMode = "first"

    def __post_init__(self) -> None:
        check_fields(self)
        if self.join not in JOIN_MODES:
            raise SettingsError(
                "join", f"must be one of {', '.join(JOIN_MODES)}, got {self.join!r}"
            )
        for name in _FLOATS:
            object.__setattr__(self, name, float(getattr(self, name)))

    def as_kwargs(self) -> dict:
        """The parameters as keyword arguments of :func:`~prg.pipeline.connect.connect_letters`."""
        return asdict(self)


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
    layout: LayoutSettings = field(default_factory=LayoutSettings)
    connection: ConnectionSettings = field(default_factory=ConnectionSettings)

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
        for name, kind in (
            ("marks", MarkSettings),
            ("layout", LayoutSettings),
            ("connection", ConnectionSettings),
        ):
            value = getattr(self, name)
            if not isinstance(value, kind):
                raise SettingsError(
                    name, f"must be a {kind.__name__}, got {type(value).__name__} {value!r}"
                )
