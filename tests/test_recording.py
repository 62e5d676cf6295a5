"""Rerun recordings: a written word with its inputs and animated DMP rollout, read back from disk."""

from __future__ import annotations

import io
import os
import shutil
import subprocess
import sys
import wave
from pathlib import Path

import numpy as np
import pytest
import torch

from prg.errors import UsageError
from prg.models.muse import MUSE
from prg.pipeline.compose import GenerateSettings
from prg.pipeline.decode import decode_letters, label_inputs
from prg.recording import (
    distinct_colours,
    read_component,
    read_entities,
    read_times,
    read_views,
    record_write,
    recording_stream,
    recording_summary,
    wav_bytes,
    waveform_envelope,
)
from prg.sim.geometry import pen_down_samples
from prg.writer import Perception, Writer

TEXT = "ab cd"
NANOSECOND = 2e-9  # times are stored as integer nanoseconds
FLOAT32 = 1e-4  # positions are stored as float32 (cm)
FLIP = np.array([1.0, -1.0])  # word y up -> Rerun 2D y down
LETTERS = ["0_a", "1_b", "2_c", "3_d"]


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
    result = Writer(model, GenerateSettings(mode="posterior")).generate(Perception(TEXT, inputs))
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


def test_the_rollout_is_animated_on_the_word_time_grid(written):
    path, rollout = written["path"], written["rollout"]
    n = len(rollout)
    summary = recording_summary(path)
    assert summary["word/rollout/pen"]["time"] == n
    # one ink segment per step whose both ends are pen-down (none across the space's travel)
    word = written["word"]
    body = slice(0, word.body_end)
    down = pen_down_samples(word.points[body], word.segment[body], word.segment_kinds, rollout)
    assert not down.all()  # "ab cd": some samples travel over the space, pen up
    assert summary["word/rollout/path"]["time"] == int((down[1:] & down[:-1]).sum())
    times = read_times(path, "word/rollout/pen", "time")
    grid = np.linspace(0, written["word"].duration_s, n)
    np.testing.assert_allclose(times, grid, atol=NANOSECOND)
    rows = read_component(path, "word/rollout/pen", "Points2D:positions", "time")
    pen = np.array([row[0] for row in rows])
    np.testing.assert_allclose(pen, rollout * FLIP, atol=FLOAT32)
    segments = read_component(path, "word/rollout/path", "LineStrips2D:strips", "time")
    np.testing.assert_allclose(segments[-1][0], rollout[-2:] * FLIP, atol=FLOAT32)


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


def test_rerun_itself_verifies_the_file(written, tmp_path):
    """The viewer's own loader (``rerun rrd verify``) reads every chunk of the recording."""
    env = {
        **os.environ,
        "HOME": str(tmp_path),
        "XDG_DATA_HOME": str(tmp_path),
        "XDG_CONFIG_HOME": str(tmp_path),
    }
    result = subprocess.run(
        [str(Path(sys.executable).parent / "rerun"), "rrd", "verify", str(written["path"])],
        capture_output=True,
        text=True,
        timeout=60,
        env=env,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert "verified without error" in result.stdout + result.stderr


def test_an_error_inside_the_stream_leaves_no_file_and_keeps_the_old_one(tmp_path):
    import rerun as rr

    target = tmp_path / "w.rrd"
    with pytest.raises(RuntimeError, match="boom"), recording_stream(target, "prg-test") as rec:
        rec.log("x", rr.TextDocument("half"), static=True)
        raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []
    target.write_bytes(b"old")
    with pytest.raises(RuntimeError, match="boom"), recording_stream(target, "prg-test") as rec:
        raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == [target] and target.read_bytes() == b"old"


def test_a_clean_stream_replaces_the_old_file(tmp_path):
    import rerun as rr

    target = tmp_path / "w.rrd"
    target.write_bytes(b"old")
    with recording_stream(target, "prg-test") as rec:
        rec.log("note", rr.TextDocument("new"), static=True)
    assert list(tmp_path.iterdir()) == [target]
    assert read_entities(target) == {"note": {"TextDocument", "TextDocument:text"}}


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


def test_reading_a_missing_or_foreign_file_names_it(tmp_path):
    with pytest.raises(UsageError, match="no such recording file"):
        read_entities(tmp_path / "none.rrd")
    junk = tmp_path / "junk.rrd"
    junk.write_bytes(b"not a recording")
    with pytest.raises(UsageError, match=r"junk\.rrd: not a readable Rerun recording"):
        read_entities(junk)


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


def test_connection_colours_are_distinct_for_long_words():
    colours = distinct_colours(40)
    assert colours.shape == (40, 3) and colours.dtype == np.uint8
    assert len({tuple(c) for c in colours}) == 40


def test_framing_bounds_hold_every_point_with_a_margin():
    from prg.recording import framing

    rng = np.random.default_rng(0)
    for scale in (0.01, 1.0, 30.0):
        pts = rng.normal(size=(50, 2)) * scale + rng.normal(size=2) * 10
        bounds = framing(pts, margin=0.1)
        (stored,) = bounds.range.as_arrow_array().to_pylist()
        (x0, x1), (y0, y1) = stored["x_range"], stored["y_range"]
        assert x0 < pts[:, 0].min() and x1 > pts[:, 0].max()
        assert y0 < pts[:, 1].min() and y1 > pts[:, 1].max()
        pad = 0.1 * max(np.ptp(pts, axis=0).max(), 1.0)
        assert np.isclose(x0, pts[:, 0].min() - pad) and np.isclose(y1, pts[:, 1].max() + pad)


def test_the_3d_eye_holds_every_point_and_is_no_farther_than_it_must_be():
    from prg.recording import framing_eye

    rng = np.random.default_rng(1)
    edge = np.tan(np.radians(55.0) / 2)  # Rerun's vertical field of view
    for aspect in (1.0, 1.6):
        for _ in range(5):
            pts = rng.normal(size=(40, 3)) * rng.uniform(0.01, 1.0, size=3) + rng.normal(size=3)
            looking_from = rng.normal(size=3) + np.array([0.0, 0.0, 2.0])
            eye = framing_eye(pts, looking_from, margin=0.1, aspect=aspect)
            (position,) = eye.position.as_arrow_array().to_pylist()
            (target,) = eye.look_target.as_arrow_array().to_pylist()
            forward = np.subtract(target, position)
            forward /= np.linalg.norm(forward)
            np.testing.assert_allclose(
                forward, -looking_from / np.linalg.norm(looking_from), atol=FLOAT32
            )
            right = np.cross(forward, [0.0, 0.0, 1.0])
            right /= np.linalg.norm(right)
            up = np.cross(right, forward)
            rel = pts - position
            depth = rel @ forward
            # the share of the picture (inside the margin) the farthest point out takes
            taken = max(
                (np.abs(rel @ right) / depth).max() / (edge * aspect / 1.1),
                (np.abs(rel @ up) / depth).max() / (edge / 1.1),
            )
            assert depth.min() > 0 and taken <= 1 + FLOAT32
            # tight: a point touches the margin, unless the eye keeps its least distance
            assert taken > 1 - FLOAT32 or depth.min() == pytest.approx(0.035, rel=FLOAT32)
