"""Tests of ``prg.files`` (moved from the suite on: all-or-nothing writes (prg.files) and signals
held over the steps that must not be cut.

A write is made to fail halfway for real: the kernel's file-size limit (RLIMIT_FSIZE) makes a
write past it fail with EFBIG, the way a full disk fails with ENOSPC. Every writer of the
project must then leave the previous file exactly as it was, no temporary file beside it, and an
error that names the output the user asked for (not a hidden temporary name))."""

from __future__ import annotations

import contextlib
import errno
import json
import os
import resource
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from prg.files import (
    atomic_path,
    remove_stale,
    staged_folder,
    staged_outputs,
    write_bytes,
    write_json,
    write_text,
)
from tests.conftest import REPO
from tests.helpers.atomic import LIMIT
from tests.helpers.write import WORD_FOLDER


@contextlib.contextmanager
def file_size_limit(limit: int = LIMIT):
    """Writes past ``limit`` bytes fail with EFBIG (SIGXFSZ ignored) inside the block."""
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    previous = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
        signal.signal(signal.SIGXFSZ, previous)


BIG = np.random.default_rng(0).random(LIMIT // 4)  # 512 KiB of float64: past the limit


def _save_split(path):
    from prg.data.store import save_split

    save_split(path, {"traj": BIG.astype(np.float32).reshape(-1, 2)})


def _save_classifier(path):
    import torch

    from prg.evaluation.classifiers import save_classifier

    model = torch.nn.Linear(400, 400)  # 640 KB of weights
    save_classifier(path, model, "traj", {"note": "test"})


def _recording(path):
    import rerun as rr

    from prg.recording import recording_stream

    with recording_stream(path, "prg-test") as rec:
        rec.log("points", rr.Points2D(BIG.reshape(-1, 2)))


# Every writer of the project, each made to fail halfway. Rerun's recording stream is tested in
# the test below the limit only: after a failed write its flush now and then waits for its dead
# writer thread (recording_stream bounds the wait, FLUSH_TIMEOUT_S), too slow for this suite.
WRITERS = {
    "write_json": lambda p: write_json(p, {"values": BIG.tolist()}),
    "write_text": lambda p: write_text(p, "x" * (2 * LIMIT)),
    "write_bytes": lambda p: write_bytes(p, b"x" * (2 * LIMIT)),
    "save_split": _save_split,
    "save_classifier": _save_classifier,
    "recording_stream": _recording,
}


def fail_one_write(writer: str, path: str) -> None:
    """Run in a child process: ``writer`` under the size limit; print the error as JSON.

    A child, because the limit is per process: in the test process it would also fail the
    writes of other threads (loggers, recording streams) that earlier tests left running.
    """
    with file_size_limit():
        try:
            WRITERS[writer](Path(path))
        except OSError as err:
            print(json.dumps({"errno": err.errno, "filename": err.filename}))
            return
    print(json.dumps({"errno": None}))


@pytest.mark.parametrize("writer", [w for w in WRITERS if w != "recording_stream"])
def test_a_write_that_fails_halfway_keeps_the_previous_file(writer, tmp_path):
    path = tmp_path / "out" / "result.bin"
    path.parent.mkdir()
    path.write_bytes(b"the previous result")
    code = f"from tests.prg.test_files import fail_one_write; fail_one_write({writer!r}, {str(path)!r})"
    child = subprocess.run(
        [sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=120
    )
    assert child.returncode == 0, child.stderr[-2000:]
    failure = json.loads(child.stdout.strip().splitlines()[-1])
    assert failure["errno"] == errno.EFBIG
    assert Path(failure["filename"]) == path  # the user's path, not a hidden temporary one
    assert path.read_bytes() == b"the previous result"
    assert sorted(p.name for p in path.parent.iterdir()) == ["result.bin"]


@pytest.mark.parametrize("writer", list(WRITERS))
def test_the_same_writes_succeed_below_the_limit(writer, tmp_path):
    """The failure above is the limit's, not the writer's (the test can tell them apart)."""
    path = tmp_path / "result.bin"
    path.write_bytes(b"the previous result")
    WRITERS[writer](path)
    assert path.read_bytes() != b"the previous result"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["result.bin"]


def test_staged_outputs_move_nothing_when_one_output_fails(tmp_path):
    target = tmp_path / "reports"
    target.mkdir()
    (target / "a.json").write_text("old a")
    (target / "b.json").write_text("old b")
    (target / "kept.txt").write_text("not ours")
    with pytest.raises(RuntimeError), staged_outputs(target) as staging:
        write_json(staging / "a.json", {"new": 1})  # complete
        write_text(staging / "b.json", "half")
        raise RuntimeError("the third output fails")
    assert {p.name: p.read_text() for p in target.iterdir()} == {
        "a.json": "old a",
        "b.json": "old b",
        "kept.txt": "not ours",
    }
    assert sorted(p.name for p in tmp_path.iterdir()) == ["reports"]
    with staged_outputs(target) as staging:
        write_json(staging / "a.json", {"new": 1})
    assert json.loads((target / "a.json").read_text()) == {"new": 1}
    assert (target / "b.json").read_text() == "old b"  # only the outputs written are replaced
    assert (target / "kept.txt").read_text() == "not ours"


def test_staged_folder_is_replaced_as_a_whole_or_not_at_all(tmp_path):
    final = tmp_path / "dataset"
    final.mkdir()
    (final / "old.npz").write_bytes(b"old")
    with pytest.raises(RuntimeError), staged_folder(final) as staging:
        (staging / "new.npz").write_bytes(b"new")
        raise RuntimeError("a bug halfway")
    assert [p.name for p in final.iterdir()] == ["old.npz"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dataset"]
    with staged_folder(final) as staging:
        (staging / "new.npz").write_bytes(b"new")
    assert [p.name for p in final.iterdir()] == ["new.npz"]  # the old entries are gone
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dataset"]


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_leftovers_of_killed_writers_are_removed_by_the_next_write(tmp_path):
    dead, alive = _dead_pid(), os.getppid()
    (tmp_path / f".dataset.tmp-{dead}").mkdir()
    (tmp_path / f".dataset.tmp-{dead}" / "train.npz").write_bytes(b"half")
    (tmp_path / f".dataset.old-{dead}").mkdir()
    (tmp_path / f".result.tmp-{dead}.png").write_bytes(b"half")
    (tmp_path / f".dataset.tmp-{alive}").mkdir()  # a write in progress elsewhere: kept
    (tmp_path / ".hidden-notes.tmp").write_text("not ours: kept")
    with staged_folder(tmp_path / "dataset") as staging:
        (staging / "x").write_text("new")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [".hidden-notes.tmp", f".dataset.tmp-{alive}", "dataset"]
    )
    assert remove_stale(tmp_path) == []


def test_atomic_path_keeps_the_suffix_for_writers_that_choose_a_format_by_it(tmp_path):
    with atomic_path(tmp_path / "figure.png") as tmp:
        assert tmp.suffix == ".png" and tmp.parent == tmp_path and tmp.name.startswith(".")
        tmp.write_bytes(b"png")
    assert (tmp_path / "figure.png").read_bytes() == b"png"


def test_folders_made_at_once_never_share_a_name_and_a_failed_one_is_removed(tmp_path):
    import re

    from prg.files import word_folder

    template = str(tmp_path / "w" / "{text}-{time}")
    made = []
    for _ in range(3):
        with word_folder(template, "ab cd!") as folder:
            made.append(folder)
    assert len(set(made)) == 3 and all(f.is_dir() for f in made)
    assert all(re.fullmatch(WORD_FOLDER, f.name) for f in made), made
    with pytest.raises(RuntimeError, match="boom"), word_folder(template, "ab cd") as folder:
        raise RuntimeError("boom")
    assert not folder.exists() and sorted((tmp_path / "w").iterdir()) == sorted(made)
    with word_folder(tmp_path / "mine", "ab cd") as folder:  # no placeholder: that folder
        assert folder == tmp_path / "mine" and not folder.exists()  # staged_outputs makes it
