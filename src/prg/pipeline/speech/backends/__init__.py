"""The recogniser back-ends (``SpeechSettings.backend``), each imported lazily
(``pip install prg[speech]``), and :func:`get_recogniser`, which builds one once per
(backend, model) and caches it.

:mod:`~prg.pipeline.speech.backends.whisper`
    ``whisper``: faster-whisper (CTranslate2), int8 on the CPU; closed-vocabulary rescoring by
    teacher forcing. The default.
:mod:`~prg.pipeline.speech.backends.wav2vec2`
    ``wav2vec2``: the paper's recogniser, ``transformers`` CTC; rescoring by CTC likelihood.
:mod:`~prg.pipeline.speech.backends.pocketsphinx`
    ``pocketsphinx``: CMU PocketSphinx 5; with a lexicon, a JSGF grammar of its words.
:mod:`~prg.pipeline.speech.backends.base`
    What a back-end is (:class:`Recogniser`) and where its model is loaded from.
"""

from __future__ import annotations

import functools
import logging
import time

from prg.pipeline.speech.backends.base import Recogniser
from prg.pipeline.speech.backends.pocketsphinx import PocketSphinxRecogniser
from prg.pipeline.speech.backends.wav2vec2 import DEFAULT_WAV2VEC2, Wav2Vec2Recogniser
from prg.pipeline.speech.backends.whisper import (
    WHISPER_PAD_S,
    WHISPER_THREADS,
    WhisperRecogniser,
)
from prg.pipeline.speech.settings import unknown_backend

log = logging.getLogger("prg.pipeline.speech")

__all__ = [
    "DEFAULT_WAV2VEC2",
    "WHISPER_PAD_S",
    "WHISPER_THREADS",
    "PocketSphinxRecogniser",
    "Recogniser",
    "Wav2Vec2Recogniser",
    "WhisperRecogniser",
    "get_recogniser",
]

_CLASSES = {
    "whisper": WhisperRecogniser,
    "wav2vec2": Wav2Vec2Recogniser,
    "pocketsphinx": PocketSphinxRecogniser,
}


@functools.lru_cache(maxsize=4)
def get_recogniser(backend: str, model: str | None = None) -> Recogniser:
    """The recogniser of ``backend`` with ``model`` (None: its default), built once and cached."""
    if backend not in _CLASSES:
        raise unknown_backend(backend)
    start = time.perf_counter()
    recogniser = _CLASSES[backend](model)
    log.info("loaded %s model %s in %.1f s", backend, recogniser.model, time.perf_counter() - start)
    return recogniser
