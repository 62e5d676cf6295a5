"""No mixed or orphaned results: a folder one training writes is refused to another run, and a
command's worker processes end with it, however it dies (SIGKILL included). Real processes."""

from __future__ import annotations

import os
import signal
import subprocess
import time

import pytest

from tests.cli.test_signals import _alive, _descendants
from tests.conftest import BIN, run_cli
from tests.helpers.train import FAST
from tests.prg.test_locks import hold


@pytest.mark.parametrize("key", ["export_dir", "checkpoint_dir"])
def test_train_refuses_a_folder_another_run_writes(tmp_path, small_dataset, key):
    folder = tmp_path / "models" / "muse"
    other = hold(folder)  # another run, between its start and its end
    try:
        result = run_cli(
            "prg-train",
            f"paths.root_dir={tmp_path}",
            f"paths.data_dir={small_dataset}",
            *FAST,
            f"export_dir={tmp_path / 'models' / 'muse'}",
            *([f"checkpoint_dir={folder}"] if key == "checkpoint_dir" else []),
        )
    finally:
        other.send_signal(signal.SIGKILL)
        other.wait()
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2, result.stderr[-3000:]
    assert len(lines) == 1, lines
    assert lines[0].startswith(f"prg-train: error: {key} {folder} is being written by another")
    assert f"pid {other.pid} on " in lines[0]
    assert not folder.exists()  # nothing of this run


def test_prepare_killed_leaves_no_worker_running(tmp_path):
    """SIGKILL gives prg-prepare no chance to stop its pool: the fork server, the workers and
    the resource tracker must end by themselves, within seconds."""
    argv = [
        str(BIN / "prg-prepare"),
        f"paths.root_dir={tmp_path}",
        f"paths.data_dir={tmp_path / 'data'}",
        "data.synthetic.n_writers=40",
        "data.augment.per_class=200",
        "workers=2",
        "progress=false",
        "figures=false",
        f"metrics_path={tmp_path / 'metrics.json'}",
    ]
    env = {**os.environ, "PRG_ROOT": str(tmp_path)}
    proc = subprocess.Popen(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    below: set[int] = set()
    try:
        deadline = time.monotonic() + 240
        while len(below) < 4:  # resource tracker, fork server, two workers
            assert proc.poll() is None, proc.stderr.read()[-2000:]
            assert time.monotonic() < deadline, "the pool never started"
            time.sleep(0.05)
            below = _descendants(proc.pid)
        time.sleep(0.5)  # the workers are fitting
        below = _descendants(proc.pid)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        grace = time.monotonic() + 5
        while _alive(below) and time.monotonic() < grace:
            time.sleep(0.1)
        left = _alive(below)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        for pid in _alive(below):
            os.kill(pid, signal.SIGKILL)
    assert not left, f"still running 5 s after prg-prepare was killed: {sorted(left)}"
    assert not (tmp_path / "data" / "prepared" / "synthetic").exists()
