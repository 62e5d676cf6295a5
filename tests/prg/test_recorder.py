"""The word's recording made in a second process (``prg.recorder``, ``prg-write``'s default):
the same recording as one made in the writer's own process, errors in one line, no process
left behind."""

from __future__ import annotations

import numpy as np
import pytest

from prg.errors import UsageError
from prg.recorder import REQUEST, RecorderProcess
from prg.recording import read_component, read_entities, read_times
from prg.writer import Writer


@pytest.fixture(scope="module")
def result(untrained_muse_checkpoint):
    return Writer.from_checkpoint(untrained_muse_checkpoint).write("ab c")


def test_the_worker_records_what_the_writer_records_itself(result, tmp_path):
    here, there = tmp_path / "here", tmp_path / "there"
    result.save(here, record=True)
    with RecorderProcess() as recorder:
        result.save(there, record=True, recorder=recorder)
    assert sorted(p.name for p in there.iterdir()) == sorted(p.name for p in here.iterdir())
    assert not (there / REQUEST).exists()
    assert read_entities(there / "word.rrd") == read_entities(here / "word.rrd")
    for path in (here, there):
        assert len(read_times(path / "word.rrd", "word/rollout/pen", "time")) > 10
    np.testing.assert_array_equal(
        read_times(there / "word.rrd", "word/rollout/pen", "time"),
        read_times(here / "word.rrd", "word/rollout/pen", "time"),
    )
    # a connection stroke, where the untrained letters do not lift the pen (lifts_pen)
    joined = "connection" in result.word.segment_kinds
    for entity in ("word/letters/0_a", *(["word/connections/0"] if joined else [])):
        strips = read_component(there / "word.rrd", entity, "LineStrips2D:strips")
        assert strips and strips == read_component(here / "word.rrd", entity, "LineStrips2D:strips")


def test_bad_input_to_the_worker_is_one_line_and_nothing_is_saved(result, tmp_path):
    folder = tmp_path / "word"
    folder.mkdir()
    result.word.to_json(folder / "word.json")
    with RecorderProcess() as recorder:
        recorder.send(folder, result.rollout, {"images": np.zeros((5, 3))})  # not letter images
        with pytest.raises(UsageError) as err:
            recorder.wait()
    assert str(err.value).startswith("the recording (word.rrd) failed: images")
    assert "\n" not in str(err.value)
    assert sorted(p.name for p in folder.iterdir()) == ["word.json"]  # no request, no .rrd


def test_a_worker_never_sent_a_word_is_stopped(tmp_path):
    with RecorderProcess() as recorder:
        process = recorder._process
    assert process.poll() is not None
