"""Audio for phi_S: a file or an array to 16 kHz mono float32, and the checks before recognition.

Audio file or array (any sample rate and channel count) -> :func:`load_audio`: 16 kHz mono
float32 (channels averaged, ``scipy.signal.resample_poly``) -> :func:`check_audio`: not empty,
not silent (RMS below ``min_rms_dbfs``), not longer than ``max_seconds``.
"""

from __future__ import annotations

import functools
import logging
import math
import os
import sys
import tempfile
from collections.abc import Iterator, Sequence
from contextlib import contextmanager, suppress
from math import gcd
from pathlib import Path

import numpy as np

from prg.errors import UsageError
from prg.pipeline.speech.dependencies import INSTALL, first_line
from prg.pipeline.speech.settings import SpeechSettings

log = logging.getLogger(__name__)

SAMPLE_RATE = 16_000  # every backend receives 16 kHz mono float32
SNDFILE_SUFFIXES = (".wav", ".flac", ".ogg", ".oga", ".aiff", ".aif", ".au", ".caf")


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

    samples = np.asarray(samples)
    g = gcd(int(rate), int(target))
    up, down = int(target) // g, int(rate) // g
    floating = np.issubdtype(samples.dtype, np.floating)
    taps = _lowpass(up, down, samples.dtype if floating else np.dtype(np.float64))
    return resample_poly(samples, up, down, window=taps)


@functools.lru_cache(maxsize=8)
def _lowpass(up: int, down: int, dtype: np.dtype) -> np.ndarray:
    """The anti-aliasing filter ``resample_poly`` designs by default for ``up / down`` (Kaiser
    window, beta 5, 10 taps per phase of the larger factor), in the dtype it would use; cached:
    designing it is most of a resampling's cost (0.6 of 0.9 ms for 1 s from 22.05 kHz)."""
    from scipy.signal import firwin

    rate = max(up, down)
    taps = firwin(2 * 10 * rate + 1, 1.0 / rate, window=("kaiser", 5.0)).astype(dtype)
    taps.setflags(write=False)  # resample_poly copies it before scaling
    return taps


def rms_dbfs(samples: np.ndarray) -> float:
    """RMS level in dB relative to full scale 1.0 (``-inf`` for digital silence)."""
    rms = float(np.sqrt(np.mean(np.square(samples, dtype=np.float64)))) if len(samples) else 0.0
    return 20.0 * math.log10(rms) if rms > 0 else -math.inf


def _too_long(name: str, seconds: float | None, max_seconds: float) -> UsageError:
    """The error for audio longer than ``max_seconds`` (``seconds``: its length, None when it was
    not decoded to the end)."""
    length = f"{seconds:.1f} s long" if seconds is not None else f"longer than {max_seconds:g} s"
    return UsageError(
        f"{name}: audio is {length}: accepted are clips up to "
        f"speech.max_seconds={max_seconds:g} s (one word or a short phrase)"
    )


@contextmanager
def _decoder_output_to_log() -> Iterator[None]:
    """While a native decoder runs, the process's stderr (file descriptor 2) goes to a temporary
    file whose text is then logged (debug): libsndfile's MP3 decoder (mpg123) writes lines such
    as ``Note: Illegal Audio-MPEG-Header ...`` to it directly when a file named ``.mp3`` is not
    one, beside the command's own one-line error."""
    with suppress(Exception):
        sys.stderr.flush()
    try:
        saved = os.dup(2)
    except OSError:  # no stderr to protect
        yield
        return
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            said = sink.read(4096).decode("utf-8", "replace").strip()
            if said:
                log.debug("audio decoder: %s", " | ".join(said.splitlines()))


def _header_seconds(path: Path) -> float | None:
    """The duration a file's header states (soundfile, else PyAV), None if none can be read."""
    try:
        import soundfile

        with _decoder_output_to_log():
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
        with _decoder_output_to_log(), soundfile.SoundFile(str(path)) as sound:
            rate = int(sound.samplerate)
            cap = sound.frames if max_seconds is None else math.floor(max_seconds * rate) + 1
            data = sound.read(frames=min(sound.frames, cap), dtype="float32", always_2d=True)
        if max_seconds is not None and len(data) > max_seconds * rate:
            raise _too_long(str(path), None, max_seconds)
        return data, rate
    except (soundfile.LibsndfileError, RuntimeError, TypeError) as err:
        sf_error = err
    if path.suffix.lower() in SNDFILE_SUFFIXES:
        raise UsageError(f"{path}: cannot read audio ({sf_error})")
    return _decode_with_ffmpeg(path, max_seconds)


def _decode_with_ffmpeg(path: Path, max_seconds: float | None) -> tuple[np.ndarray, int]:
    """(16 kHz mono samples, 16 000) of a file FFmpeg decodes (MP3, M4A, WebM, ...), through PyAV.

    Decoded frame by frame, so that a file longer than ``max_seconds`` is refused as soon as
    that much has been decoded, also when its header states no duration (a raw stream), rather
    than after decoding it whole (``faster_whisper.audio.decode_audio`` has no such limit).
    """
    try:
        import av
    except ImportError:
        raise UsageError(
            f"{path}: not a WAV/FLAC/OGG file, and other formats need PyAV: {INSTALL}"
        ) from None
    limit = math.inf if max_seconds is None else max_seconds * SAMPLE_RATE
    chunks, total = [], 0
    try:
        with av.open(str(path)) as container:
            if not container.streams.audio:
                raise ValueError("no audio stream")
            stream = container.streams.audio[0]
            resampler = av.AudioResampler(format="flt", layout="mono", rate=SAMPLE_RATE)
            for frame in container.decode(stream):
                for out in resampler.resample(frame):
                    chunk = out.to_ndarray().reshape(-1)
                    chunks.append(chunk)
                    total += len(chunk)
                if total > limit:
                    raise _too_long(str(path), None, max_seconds)
            for out in resampler.resample(None):
                chunks.append(out.to_ndarray().reshape(-1))
    except UsageError:
        raise
    except Exception as err:
        raise UsageError(
            f"{path}: not an audio file that can be read (accepted: WAV, FLAC, OGG, and "
            f"formats FFmpeg decodes such as MP3); {first_line(err)}"
        ) from None
    samples = np.concatenate(chunks) if chunks else np.zeros(0, np.float32)
    return samples.astype(np.float32, copy=False), SAMPLE_RATE


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
