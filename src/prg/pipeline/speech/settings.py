"""How phi_S recognises speech: :class:`SpeechSettings`, and the back-ends and cases it accepts."""

from __future__ import annotations

import math
from dataclasses import dataclass

from prg.errors import UsageError

BACKENDS = ("whisper", "wav2vec2", "pocketsphinx")
CASES = ("lower", "upper", "title")


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
        Spoken language (whisper; English-only models ignore it).
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
        if self.backend not in BACKENDS:
            raise unknown_backend(self.backend)
        if self.case not in CASES:
            raise UsageError(f"case {self.case!r} is unknown: accepted are {', '.join(CASES)}")
        if self.model is not None:
            object.__setattr__(self, "model", str(self.model))
        if not 0 < self.max_seconds < math.inf:
            raise UsageError(f"max_seconds must be > 0 and finite, got {self.max_seconds}")
        if not 0 <= self.prior_weight <= 1:
            raise UsageError(f"prior_weight must be between 0 and 1, got {self.prior_weight}")
        if not 1 <= self.slowdown <= 2:
            raise UsageError(f"slowdown must be between 1 and 2, got {self.slowdown}")
        if not 0 <= self.noise_subtraction <= 10:
            raise UsageError(
                f"noise_subtraction must be between 0 and 10, got {self.noise_subtraction}"
            )
        if not self.view_margin >= 0:
            raise UsageError(f"view_margin must be >= 0, got {self.view_margin}")
        if not 0 <= self.min_lead < math.inf:
            raise UsageError(f"min_lead must be >= 0 and finite, got {self.min_lead}")
        if not (isinstance(self.beam_size, int) and self.beam_size >= 1):
            raise UsageError(f"beam_size must be an integer >= 1, got {self.beam_size!r}")
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
        if self.rescore and self.lexicon is None:
            raise UsageError("rescore=True needs a lexicon: the words to choose from")
        if self.rescore and self.backend == "pocketsphinx":
            raise UsageError(
                "rescore is for whisper and wav2vec2; pocketsphinx with a lexicon already "
                "decodes a closed vocabulary (its grammar)"
            )
