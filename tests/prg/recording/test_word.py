"""Tests of ``prg.recording.word`` (moved from the suite on: rerun recordings: a written word with
its inputs and animated DMP rollout, read back from disk)."""

from __future__ import annotations

import io
import wave

import numpy as np
import pytest

from prg.errors import UsageError
from prg.recording import (
    read_component,
    read_entities,
    read_times,
    read_views,
    record_write,
)
from tests.helpers.recording import FLIP, FLOAT32, NANOSECOND, written  # noqa: F401 (fixtures)

LETTERS = ["0_a", "1_b", "2_c", "3_d"]


def _unpack(colour: int) -> tuple[int, int, int]:
    return (colour >> 24) & 255, (colour >> 16) & 255, (colour >> 8) & 255


def test_the_inputs_word_parts_and_rollout_are_all_in_the_file(written):
    entities = read_entities(written["path"])
    word = written["word"]
    n_connections = word.segment_kinds.count("connection")
    assert "AssetAudio" in entities["inputs/audio"]
    assert "Scalars" in entities["inputs/waveform"]
    assert "TextDocument:text" in entities["inputs/transcript"]
    assert {e for e in entities if e.startswith("inputs/images/")} == {
        f"inputs/images/{n}" for n in LETTERS
    }
    assert {e for e in entities if e.startswith("decoded/")} == {f"decoded/{n}" for n in LETTERS}
    assert {e for e in entities if e.startswith("word/letters/")} == {
        f"word/letters/{n}" for n in LETTERS
    }
    assert {e for e in entities if e.startswith("word/connections/")} == {
        f"word/connections/{j}" for j in range(n_connections)
    }
    assert n_connections == 2
    assert set(entities) >= {"word/pen_up/0", "word/target", "summary"}
    assert "Points2D:positions" in entities["word/rollout/pen"]
    assert "LineStrips2D:strips" in entities["word/rollout/path"]


def test_positions_are_centimetres_with_y_flipped_for_the_y_down_viewer(written):
    (target,) = read_component(written["path"], "word/target", "LineStrips2D:strips")
    np.testing.assert_allclose(np.array(target[0]), written["word"].points * FLIP, atol=FLOAT32)
    (letter,) = read_component(written["path"], "word/letters/1_b", "LineStrips2D:strips")
    _, b = written["word"].letters[1]
    np.testing.assert_allclose(np.array(letter[0]), b * FLIP, atol=FLOAT32)


def test_letters_share_one_ink_and_each_connection_has_its_own_colour(written):
    path = written["path"]
    inks = {
        _unpack(read_component(path, f"word/letters/{n}", "LineStrips2D:colors")[0][0])
        for n in LETTERS
    }
    links = [
        _unpack(read_component(path, f"word/connections/{j}", "LineStrips2D:colors")[0][0])
        for j in range(2)
    ]
    assert len(inks) == 1 and len(set(links)) == 2 and not inks & set(links)


def test_the_speech_is_playable_and_plotted_before_the_writing_starts(written):
    path, audio, rate = written["path"], written["audio"], written["rate"]
    (blob,) = read_component(path, "inputs/audio", "AssetAudio:blob")
    with wave.open(io.BytesIO(bytes(blob[0])), "rb") as f:
        assert f.getframerate() == rate
        np.testing.assert_array_equal(np.frombuffer(f.readframes(len(audio) + 1), "<i2"), audio)
    seconds = len(audio) / rate
    on_audio = read_times(path, "inputs/waveform", "audio_time")
    on_time = read_times(path, "inputs/waveform", "time")
    assert on_audio[0] == 0 and on_audio[-1] < seconds
    np.testing.assert_allclose(on_time, on_audio - seconds, atol=NANOSECOND)
    bucket = -(-len(audio) // 2000)  # samples per row: the plot has at most 2000 rows
    assert len(on_audio) == -(-len(audio) // bucket) <= 2000


def test_the_file_is_renamed_into_place_and_carries_a_blueprint(written):
    from rerun.chunk import RrdReader

    folder = written["path"].parent
    assert [p.name for p in folder.iterdir()] == ["word.rrd"]
    assert len(RrdReader(written["path"]).blueprints()) == 1


def _inside(bounds: dict, points: np.ndarray) -> bool:
    """Every point strictly inside 2D view bounds (``VisualBounds2D:range``)."""
    (x0, x1), (y0, y1) = bounds["x_range"], bounds["y_range"]
    x, y = np.asarray(points).reshape(-1, 2).T
    return bool(x0 < x.min() and x.max() < x1 and y0 < y.min() and y.max() < y1)


def test_the_word_and_every_decoded_letter_open_whole_in_their_views(written):
    """The stored blueprint bounds the word view around the word and the letter strip around
    every letter where the recording places it (its strip moved by its transform)."""
    path = written["path"]
    views = read_views(path)
    assert _inside(views["Word: ab cd"]["VisualBounds2D:range"], written["word"].points * FLIP)
    strip = views["Decoded letters"]["VisualBounds2D:range"]
    shown = []
    for name in LETTERS:
        ((points,),) = read_component(path, f"decoded/{name}", "LineStrips2D:strips")
        ((shift,),) = read_component(path, f"decoded/{name}", "Transform3D:translation")
        shown.append(np.asarray(points) + shift[:2])
        assert _inside(strip, shown[-1]), name
    (x0, x1), _ = strip["x_range"], strip["y_range"]
    first, last = shown[0][:, 0].min(), shown[-1][:, 0].max()
    assert x0 < first - 0.05 * (last - first) and x1 > last + 0.05 * (last - first)  # a margin
    assert views["Waveform"]["PlotLegend:visible"] is False  # its min/max key hid the curve


def test_inputs_of_the_wrong_shape_are_refused_by_name_and_nothing_is_written(written, tmp_path):
    word, rollout = written["word"], written["rollout"]
    target = tmp_path / "bad.rrd"
    with pytest.raises(UsageError, match=r"images must have shape \(4, H, W\)"):
        record_write(target, word, rollout, images=np.zeros((3, 28, 28)))
    with pytest.raises(UsageError, match=r"rollout must have shape \(n, 2\)"):
        record_write(target, word, rollout[:, :1])
    with pytest.raises(UsageError, match="sample_rate must be a positive integer"):
        record_write(target, word, rollout, audio=np.zeros(100), sample_rate=0)
    assert list(tmp_path.iterdir()) == []
