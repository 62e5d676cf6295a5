"""Tests of ``prg.recording.audio`` (moved from the suite on: rerun recordings: a written word with
its inputs and animated DMP rollout, read back from disk)."""

from __future__ import annotations

import io
import wave

import numpy as np
import pytest

from prg.recording import (
    wav_bytes,
    waveform_envelope,
)


def test_the_waveform_envelope_keeps_every_extreme_and_caps_its_length():
    rng = np.random.default_rng(0)
    audio = rng.uniform(-0.9, 0.9, 10_001)
    audio[1234], audio[8765] = 0.99, -0.98
    t, low, high = waveform_envelope(audio, 8000, max_points=100)
    assert len(t) <= 100 and np.all(np.diff(t) > 0) and t[0] == 0
    assert high.max() == pytest.approx(0.99) and low.min() == pytest.approx(-0.98)
    assert np.all(low <= high)
    t, low, high = waveform_envelope(audio[:50], 8000, max_points=100)  # short: every sample
    np.testing.assert_array_equal(low, audio[:50])
    np.testing.assert_array_equal(high, audio[:50])


def test_wav_encoding_round_trips_float_and_int16_samples():
    samples = np.array([0.0, 0.5, -0.5, 1.0, -1.0, 2.0])
    with wave.open(io.BytesIO(wav_bytes(samples, 8000)), "rb") as f:
        assert (f.getnchannels(), f.getsampwidth(), f.getframerate()) == (1, 2, 8000)
        pcm = np.frombuffer(f.readframes(f.getnframes()), dtype="<i2")
    np.testing.assert_array_equal(pcm, [0, 16384, -16384, 32767, -32767, 32767])  # 2.0 clipped
    ints = np.array([[1, -2], [32767, -32768]], dtype=np.int16)
    with wave.open(io.BytesIO(wav_bytes(ints, 22050)), "rb") as f:
        assert f.getnchannels() == 2
        pcm = np.frombuffer(f.readframes(f.getnframes()), dtype="<i2")
    np.testing.assert_array_equal(pcm, ints.reshape(-1))
