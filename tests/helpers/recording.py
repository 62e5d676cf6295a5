"""Helpers shared by the tests that were split out of tests/test_recording.py."""

from __future__ import annotations

import shutil
import subprocess
import wave
from pathlib import Path

import numpy as np
import pytest
import torch

from prg.models.muse import MUSE
from prg.pipeline.compose import GenerateSettings
from prg.pipeline.decode import decode_letters, label_inputs
from prg.recording import (
    record_write,
)
from prg.writer import Perception, Writer

TEXT = "ab cd"


NANOSECOND = 2e-9  # times are stored as integer nanoseconds


FLOAT32 = 1e-4  # positions are stored as float32 (cm)


FLIP = np.array([1.0, -1.0])  # word y up -> Rerun 2D y down


def _speech(tmp_path: Path) -> tuple[np.ndarray, int]:
    """The word spoken by espeak-ng (int16 samples), or a 0.5 s tone where it is not installed."""
    espeak = shutil.which("espeak-ng")
    if espeak is None:
        rate = 16000
        tone = 0.5 * np.sin(2 * np.pi * 220 * np.arange(rate // 2) / rate)
        return np.round(tone * 32767).astype(np.int16), rate
    wav = tmp_path / "speech.wav"
    subprocess.run([espeak, "-w", str(wav), TEXT], check=True, capture_output=True, timeout=30)
    with wave.open(str(wav), "rb") as f:
        frames = f.readframes(f.getnframes())
        return np.frombuffer(frames, dtype="<i2").copy(), f.getframerate()


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """A word written by an untrained MUSE (real layout, connections, DMP), its inputs, a file."""
    tmp = tmp_path_factory.mktemp("rec")
    torch.manual_seed(0)
    model = MUSE().eval()
    inputs = label_inputs(TEXT)
    # the paper's joins: an untrained model's scribbles leave the hand joins no clean stroke
    settings = GenerateSettings(mode="posterior", method="alg1")
    result = Writer(model, settings).generate(Perception(TEXT, inputs))
    word, rollout = result.word, result.rollout
    letters = decode_letters(model, inputs)
    images = np.random.default_rng(0).random((4, 1, 28, 28)).astype(np.float32)
    audio, rate = _speech(tmp)
    path = record_write(
        tmp / "out" / "word.rrd",
        word,
        rollout,
        letters=letters,
        images=images,
        audio=audio,
        sample_rate=rate,
        transcript=TEXT,
    )
    return {"path": path, "word": word, "rollout": rollout, "audio": audio, "rate": rate}
