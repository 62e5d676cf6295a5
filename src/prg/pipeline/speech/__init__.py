"""The Perceive stage's speech map phi_S: a spoken word to the text (letter labels) to write.

Audio file or array (any sample rate and channel count)
-> :func:`load_audio`: 16 kHz mono float32 (channels averaged, ``scipy.signal.resample_poly``)
-> checks: not empty, not silent (RMS below ``min_rms_dbfs``), not longer than ``max_seconds``
-> a recogniser backend: raw transcript
-> :func:`transcript_to_word`: letters and digits only, words separated by one space, case applied
-> the text to write, whose characters are all in :mod:`prg.alphabet`.

Spoken words carry no case, so the case of the written word is a choice (``SpeechSettings.case``).

Modules
-------
:mod:`~prg.pipeline.speech.settings`
    :class:`SpeechSettings`: back-end, model, lexicon, rescoring, case, limits.
:mod:`~prg.pipeline.speech.audio`
    :func:`load_audio` and :func:`check_audio`, with their pure helpers.
:mod:`~prg.pipeline.speech.transcript`
    :class:`Transcript`, :func:`transcript_to_word`, lexicon snapping and letter error rate.
:mod:`~prg.pipeline.speech.backends`
    The recognisers (whisper, wav2vec2, pocketsphinx), each imported lazily
    (``pip install prg[speech]``), built once per (backend, model) and cached
    (:func:`get_recogniser`).
:mod:`~prg.pipeline.speech.perceive`
    :func:`recognise` and :func:`perceive_speech`: phi_S end to end.
:mod:`~prg.pipeline.speech.dependencies`
    What to install when an optional dependency is missing.
"""

from __future__ import annotations

from prg.pipeline.speech.audio import (
    SAMPLE_RATE,
    SNDFILE_SUFFIXES,
    check_audio,
    load_audio,
    resample,
    rms_dbfs,
    to_float,
    to_mono,
)
from prg.pipeline.speech.backends import (
    DEFAULT_WAV2VEC2,
    WHISPER_PAD_S,
    WHISPER_THREADS,
    PocketSphinxRecogniser,
    Recogniser,
    Wav2Vec2Recogniser,
    WhisperRecogniser,
    get_recogniser,
)
from prg.pipeline.speech.dependencies import INSTALL
from prg.pipeline.speech.perceive import perceive_speech, recognise
from prg.pipeline.speech.settings import BACKENDS, CASES, SpeechSettings
from prg.pipeline.speech.transcript import (
    Transcript,
    edit_distance,
    letter_error_rate,
    snap_to_lexicon,
    transcript_to_word,
)

__all__ = [
    "BACKENDS",
    "CASES",
    "DEFAULT_WAV2VEC2",
    "INSTALL",
    "SAMPLE_RATE",
    "SNDFILE_SUFFIXES",
    "WHISPER_PAD_S",
    "WHISPER_THREADS",
    "PocketSphinxRecogniser",
    "Recogniser",
    "SpeechSettings",
    "Transcript",
    "Wav2Vec2Recogniser",
    "WhisperRecogniser",
    "check_audio",
    "edit_distance",
    "get_recogniser",
    "letter_error_rate",
    "load_audio",
    "perceive_speech",
    "recognise",
    "resample",
    "rms_dbfs",
    "snap_to_lexicon",
    "to_float",
    "to_mono",
    "transcript_to_word",
]
