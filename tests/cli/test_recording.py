"""Rerun recordings: a written word with its inputs and animated DMP rollout, read back from disk."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from tests.helpers.recording import written  # noqa: F401 (fixtures)


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
