"""Audio for a recording: validated samples, a 16-bit PCM WAV in memory, the waveform's envelope."""

from __future__ import annotations

import io
import wave

import numpy as np

from prg.errors import UsageError


def audio_samples(audio: np.ndarray) -> np.ndarray:
    """Validated samples, float64 in [-1, 1], shape (n, channels)."""
    samples = np.asarray(audio)
    if samples.ndim == 1:
        samples = samples[:, None]
    if samples.ndim != 2 or samples.shape[0] == 0 or samples.shape[1] == 0:
        raise UsageError(f"audio must have shape (n,) or (n, channels), got {samples.shape}")
    if samples.dtype == np.int16:
        return samples.astype(np.float64) / 32768.0
    if samples.dtype.kind != "f":
        raise UsageError(f"audio samples must be float in [-1, 1] or int16, got {samples.dtype}")
    if not np.all(np.isfinite(samples)):
        raise UsageError("audio samples contain NaN or infinite values")
    return np.clip(samples.astype(np.float64), -1.0, 1.0)


def sample_rate_hz(sample_rate: int) -> int:
    """A validated sample rate: a positive integer (Hz)."""
    if isinstance(sample_rate, bool) or int(sample_rate) != sample_rate or sample_rate <= 0:
        raise UsageError(f"sample_rate must be a positive integer (Hz), got {sample_rate!r}")
    return int(sample_rate)


def wav_bytes(audio: np.ndarray, sample_rate: int) -> bytes:
    """Encode samples as a 16-bit PCM WAV file in memory.

    Parameters
    ----------
    audio : ndarray, shape (n,) or (n, channels)
        Float samples in [-1, 1] (clipped, scaled by 32767) or int16 (written as given).
    sample_rate : int
        Hz.

    Returns
    -------
    bytes
    """
    samples = audio_samples(audio)
    raw = np.asarray(audio)
    if raw.dtype == np.int16:  # as given, bit for bit
        pcm = raw.reshape(samples.shape).astype("<i2")
    else:
        pcm = np.round(samples * 32767.0).astype("<i2")
    buffer = io.BytesIO()
    with wave.open(buffer, "wb") as out:
        out.setnchannels(samples.shape[1])
        out.setsampwidth(2)
        out.setframerate(sample_rate_hz(sample_rate))
        out.writeframes(pcm.tobytes())
    return buffer.getvalue()


def waveform_envelope(
    audio: np.ndarray, sample_rate: int, max_points: int = 2000
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Min/max envelope of a (mono-mixed) waveform over buckets of consecutive samples.

    Parameters
    ----------
    audio : ndarray, shape (n,) or (n, channels)
    sample_rate : int
    max_points : int
        Most buckets returned; the bucket size is ``ceil(n / max_points)`` samples.

    Returns
    -------
    t : ndarray, shape (m,)
        Start time of each bucket (seconds).
    low, high : ndarray, shape (m,)
        Smallest and largest sample of each bucket (equal when a bucket is one sample).
    """
    samples = audio_samples(audio).mean(axis=1)
    rate = sample_rate_hz(sample_rate)
    if max_points < 1:
        raise UsageError(f"max_points must be at least 1, got {max_points}")
    size = -(-len(samples) // max_points)
    m = -(-len(samples) // size)
    padded = np.concatenate([samples, np.full(m * size - len(samples), samples[-1])])
    buckets = padded.reshape(m, size)
    return np.arange(m) * size / rate, buckets.min(axis=1), buckets.max(axis=1)
