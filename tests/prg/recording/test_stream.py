"""Tests of ``prg.recording.stream`` (moved from the suite on: rerun recordings: a written word
with its inputs and animated DMP rollout, read back from disk)."""

from __future__ import annotations

import pytest

from prg.recording import (
    read_entities,
    recording_stream,
)


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
