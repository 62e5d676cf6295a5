"""How phi_S recognises speech: :class:`SpeechSettings`, and the back-ends and cases it accepts."""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

from prg.errors import SettingsError, UsageError

BACKENDS = ("whisper", "wav2vec2", "pocketsphinx")
CASES = ("lower", "upper", "title")
# The language codes whisper decodes (``speech.language``); English-only models read English.
_LANGUAGE_CODES = (
    "af am ar as az ba be bg bn bo br bs ca cs cy da de el en es et eu fa fi fo fr gl gu ha haw "
    "he hi hr ht hu hy id is it ja jw ka kk km kn ko la lb ln lo lt lv mg mi mk ml mn mr ms mt "
    "my ne nl nn no oc pa pl ps pt ro ru sa sd si sk sl sn so sq sr su sv sw ta te tg th tk tl "
    "tr tt uk ur uz vi yi yo zh yue"
)
LANGUAGES = tuple(_LANGUAGE_CODES.split())
_NUMBERS = (
    "prior_weight",
    "slowdown",
    "view_margin",
    "min_lead",
    "noise_subtraction",
    "max_seconds",
    "min_rms_dbfs",
    "beam_size",
)


def unknown_backend(backend: str) -> UsageError:
    """The error for a back-end name that is not one of :data:`BACKENDS`."""
    return UsageError(f"speech backend {backend!r} is unknown: accepted are {', '.join(BACKENDS)}")


@dataclass(frozen=True)
class SpeechSettings:
    """How phi_S recognises speech.

    Parameters
    ----------
    backend : {"whisper", "wav2vec2", "pocketsphinx"}
    model : str or None
        Backend model (folder or cached hub name); None for the backend's default.
    lexicon : tuple of str or None
        Closed list of words (or short phrases) the speaker may say; any sequence is accepted and
        stored as a tuple. Entries must contain letters or digits.
    rescore : bool
        Choose the lexicon word the model scores highest instead of transcribing freely
        (whisper, wav2vec2); needs a lexicon.
    prior_weight : float
        Whisper rescoring: subtract this times each word's log-probability on silence from its
        log-probability on the audio (0: the plain probability; 1: pointwise mutual
        information). Takes back the decoder's preference for words it expects anyway.
    slowdown : float
        Whisper rescoring: also score the audio slowed down by this factor (1 to 2; 1: the
        audio alone) and sum the two log-probabilities, when ``view_margin`` calls for it.
    view_margin : float
        Whisper rescoring with a slowdown: when the best word on the audio alone leads every
        other word by at least this many nats (natural-log probability), the slowed copy is not
        scored (>= 0; inf: always score both).
    min_lead : float
        Rescoring: answer only when the chosen word is ahead of every other lexicon word by at
        least this many nats (>= 0; 0: always answer); otherwise :func:`recognise` raises
        :class:`~prg.errors.UncertainWordError`, naming the best word and a rival within
        ``min_lead`` of it, so that a robot can ask the speaker to repeat instead of writing a
        word it is unsure of.
    noise_subtraction : float
        Whisper on the short window (rescoring, and free transcription of a word or two):
        spectral subtraction before the encoder, for stationary noise (0 to 10; 0: off): this
        many times the mean mel power of the audio's quietest frames is taken from every frame
        (:func:`~prg.pipeline.speech.backends.whisper.subtract_noise`).
    case : {"lower", "upper", "title"}
        Case of the written word.
    max_seconds : float
        Longest accepted audio (Whisper sees 30 s at once).
    min_rms_dbfs : float
        Audio whose RMS level (dB relative to full scale 1.0) is below this is silent.
    beam_size : int
        Beam width of the whisper decoder.
    language : str
        Spoken language, one of whisper's codes (:data:`LANGUAGES`; English-only models and the
        other back-ends read English whatever it says).

    Every number must also lie in the range its ``prg-write`` option ``speech.<field>``
    accepts (:data:`prg.checks.TABLE`), so settings built in Python refuse what the commands
    refuse; ``view_margin`` may also be infinite (always score both views).
    """

    backend: str = "whisper"
    model: str | None = None
    lexicon: tuple[str, ...] | None = None
    rescore: bool = False
    prior_weight: float = 0.4
    slowdown: float = 1.1
    view_margin: float = 2.0
    min_lead: float = 0.0
    noise_subtraction: float = 1.5
    case: str = "lower"
    max_seconds: float = 30.0
    min_rms_dbfs: float = -50.0
    beam_size: int = 5
    language: str = "en"

    def __post_init__(self) -> None:
        for name in _NUMBERS:
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, numbers.Real):
                raise SettingsError(name, f"must be a number, got {value!r}")
        if not isinstance(self.rescore, bool):
            raise SettingsError("rescore", f"must be true or false, got {self.rescore!r}")
        if not isinstance(self.language, str) or self.language not in LANGUAGES:
            raise SettingsError(
                "language",
                f"{self.language!r} is unknown: accepted are whisper's language codes "
                f"({', '.join(LANGUAGES)})",
            )
        if self.backend not in BACKENDS:
            raise unknown_backend(self.backend)
        if self.case not in CASES:
            raise SettingsError(
                "case", f"{self.case!r} is unknown: accepted are {', '.join(CASES)}"
            )
        if self.model is not None:
            object.__setattr__(self, "model", str(self.model))
        if not 0 < self.max_seconds < math.inf:
            raise SettingsError("max_seconds", f"must be > 0 and finite, got {self.max_seconds}")
        if not 0 <= self.prior_weight <= 1:
            raise SettingsError("prior_weight", f"must be between 0 and 1, got {self.prior_weight}")
        if not 1 <= self.slowdown <= 2:
            raise SettingsError("slowdown", f"must be between 1 and 2, got {self.slowdown}")
        if not 0 <= self.noise_subtraction <= 10:
            raise SettingsError(
                "noise_subtraction", f"must be between 0 and 10, got {self.noise_subtraction}"
            )
        if not self.view_margin >= 0:
            raise SettingsError("view_margin", f"must be >= 0, got {self.view_margin}")
        if not 0 <= self.min_lead < math.inf:
            raise SettingsError("min_lead", f"must be >= 0 and finite, got {self.min_lead}")
        if not (isinstance(self.beam_size, int) and self.beam_size >= 1):
            raise SettingsError("beam_size", f"must be an integer >= 1, got {self.beam_size!r}")
        if self.lexicon is not None:
            if isinstance(self.lexicon, str):
                raise UsageError(
                    f"lexicon must be a list of words, got the string {self.lexicon!r}"
                )
            words = tuple(" ".join(str(w).split()) for w in self.lexicon)
            bad = [w for w in words if not any(c.isalnum() for c in w)]
            if not words or bad:
                raise UsageError(
                    f"lexicon entries must contain letters or digits, got {list(self.lexicon)!r}"
                )
            object.__setattr__(self, "lexicon", tuple(dict.fromkeys(words)))
        self._check_ranges()
        if self.rescore and self.lexicon is None:
            raise UsageError("rescore=True needs a lexicon: the words to choose from")
        if self.rescore and self.backend == "pocketsphinx":
            raise UsageError(
                "rescore is for whisper and wav2vec2; pocketsphinx with a lexicon already "
                "decodes a closed vocabulary (its grammar)"
            )

    def _check_ranges(self) -> None:
        """Each number in the range of its config option ``speech.<field>``."""
        from prg.checks import TABLE, require_number

        for name in _NUMBERS:
            value = getattr(self, name)
            if name == "view_margin" and value == math.inf:
                continue
            spec = TABLE.get(f"speech.{name}")
            if spec is not None:
                require_number(value, name, spec)
