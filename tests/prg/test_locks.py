"""prg.locks: one run at a time per output folder, released however the holder dies."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from prg.errors import UsageError
from prg.locks import folder_lock, folder_locks, lock_path

HOLD = """
import sys, time
from prg.locks import folder_lock
with folder_lock(sys.argv[1], "export_dir"):
    print("held", flush=True)
    time.sleep(600)
"""


def hold(folder: Path) -> subprocess.Popen:
    """A real process holding ``folder``'s lock until it is killed."""
    proc = subprocess.Popen(
        [sys.executable, "-c", HOLD, str(folder)], stdout=subprocess.PIPE, text=True
    )
    assert proc.stdout.readline().strip() == "held"
    return proc


def test_a_second_holder_is_refused_naming_the_first_until_it_is_killed(tmp_path):
    folder = tmp_path / "models" / "muse"
    holder = hold(folder)
    try:
        with pytest.raises(UsageError) as refused, folder_lock(folder, "export_dir"):
            pass
        message = str(refused.value)
        assert "\n" not in message
        assert f"export_dir {folder} is being written by another run" in message
        assert f"pid {holder.pid} on " in message
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait()
    # SIGKILL ran no cleanup: the kernel released the lock with the process
    with folder_lock(folder, "export_dir"):
        assert f"pid {os.getpid()} " in lock_path(folder).read_text()
        assert not folder.exists()  # the folder holds outputs only: the lock is beside it
    assert not lock_path(folder).exists()  # released: nothing left beside the outputs


def test_a_lock_file_removed_while_being_taken_is_taken_again(tmp_path, monkeypatch):
    """A run that opened the lock file just as its holder removed it locks the new file."""
    import prg.locks

    folder = tmp_path / "out"
    real_names, calls = prg.locks._names, []

    def removed_once(path, fd):
        calls.append(path)
        if len(calls) == 1:  # as if the previous holder unlinked it right after our open
            path.unlink()
        return real_names(path, fd)

    monkeypatch.setattr(prg.locks, "_names", removed_once)
    with folder_lock(folder, "export_dir"):
        assert len(calls) == 2
        assert f"pid {os.getpid()} " in lock_path(folder).read_text()


def test_the_same_folder_under_two_keys_is_locked_once(tmp_path):
    both = [(tmp_path / "a", "checkpoint_dir"), (tmp_path / "b/../a", "export_dir")]
    with (
        folder_locks(both),
        pytest.raises(UsageError, match="being written"),
        folder_lock(tmp_path / "a", "x"),
    ):
        pass


def test_a_folder_that_cannot_be_made_is_one_line(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    with (
        pytest.raises(UsageError, match=f"export_dir {blocker}/sub: cannot create its lock"),
        folder_lock(blocker / "sub", "export_dir"),
    ):
        pass


def test_lock_is_held_by_the_process_not_inherited_by_its_children(tmp_path):
    """The lock file's descriptor is close-on-exec: a child started during the run (a launcher,
    a subprocess) cannot keep the folder locked after the run ends."""
    with folder_lock(tmp_path, "export_dir"):
        child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        start = time.monotonic()
        with folder_lock(tmp_path, "export_dir"):
            assert time.monotonic() - start < 5
    finally:
        child.kill()
        child.wait()
