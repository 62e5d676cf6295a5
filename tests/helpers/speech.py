"""Helpers shared by the tests that were split out of tests/test_speech.py."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from prg.pipeline.speech import (
    get_recogniser,
)

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
