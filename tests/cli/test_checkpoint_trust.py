"""A checkpoint is data: opening one never runs code, and it may only name the project's models
and torch's optimizers and schedulers to build."""

from __future__ import annotations

import os
import subprocess
import sys

from tests.helpers.checkpoint_trust import _hostile_pickle


def test_prg_write_refuses_a_hostile_checkpoint_in_one_line_and_creates_nothing(tmp_path):
    marker = tmp_path / "pwned"
    ckpt = tmp_path / "evil.ckpt"
    _hostile_pickle(ckpt, marker)
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "prg.commands.write",
            "text=cat",
            f"ckpt={ckpt}",
            f"out_dir={tmp_path}/o",
        ],
        cwd=tmp_path,
        env={**os.environ, "PRG_ROOT": str(tmp_path)},  # logs there, not in the checkout
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 2, result.stderr
    lines = [x for x in result.stderr.splitlines() if x.strip()]
    assert len(lines) == 1 and "refused" in lines[0] and str(ckpt) in lines[0], result.stderr
    assert not marker.exists() and not (tmp_path / "o").exists()
