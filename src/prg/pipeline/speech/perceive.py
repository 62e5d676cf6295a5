"""phi_S itself: audio in, the text to write (and the transcript it came from) out."""

from __future__ import annotations

import logging
import os
import time

import numpy as np

from prg.alphabet import text_to_labels
from prg.errors import UncertainWordError, UsageError
from prg.pipeline.speech.audio import SAMPLE_RATE, check_audio, load_audio
from prg.pipeline.speech.backends import get_recogniser
from prg.pipeline.speech.settings import SpeechSettings
from prg.pipeline.speech.transcript import (
    Transcript,
    lexicon_key,
    snap_to_lexicon,
    transcript_to_word,
)

log = logging.getLogger("prg.pipeline.speech")

_N_CANDIDATES = 5  # best lexicon words kept in Transcript.candidates


def recognise(
    audio: str | os.PathLike | np.ndarray,
    params: SpeechSettings | None = None,
    sample_rate: int | None = None,
    name: str | None = None,
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
    name : str, optional
        What error messages call an array (e.g. the file it was read from); default
        "audio array".

    Returns
    -------
    Transcript

    Raises
    ------
    UncertainWordError
        Rescoring: no lexicon word leads the others by ``params.min_lead`` (a
        :class:`~prg.errors.UsageError`; ask the speaker to repeat).
    UsageError
        Unreadable/missing file, empty, silent or too long audio, a transcript with no usable
        letters, an unknown backend, a missing model or optional dependency.
    """
    params = SpeechSettings() if params is None else params
    if isinstance(audio, str | os.PathLike):
        name = str(audio)
    elif name is None:
        name = "audio array"
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
        if len(candidates) > 1 and candidates[0][1] - candidates[1][1] < params.min_lead:
            (best, top), (second, runner_up) = candidates[:2]
            raise UncertainWordError(
                f"{name}: not sure whether {best!r} or {second!r} was said ({best!r} ahead by "
                f"{top - runner_up:.2f} nats, under speech.min_lead={params.min_lead:g}); "
                "say it again",
                candidates,
            )
    else:
        text = chosen = recogniser.transcribe(samples, params)
        if params.lexicon and lexicon_key(text):
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
    name: str | None = None,
) -> tuple[str, Transcript]:
    """phi_S: audio to the text to write (and the transcript it came from).

    Returns
    -------
    text : str
        Alphabet characters (0-9, A-Z, a-z), words separated by single spaces; its letters
        map to class labels with :func:`prg.alphabet.text_to_labels`.
    transcript : Transcript
    """
    transcript = recognise(audio, params, sample_rate, name)
    for part in transcript.word.split(" "):
        text_to_labels(part)  # guaranteed by transcript_to_word; fails loudly if not
    return transcript.word, transcript
