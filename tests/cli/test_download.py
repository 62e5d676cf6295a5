"""Tests of the atomic downloader and UJI fetching against a real HTTP server on loopback."""

from __future__ import annotations

import os
from pathlib import Path

from prg.data.download import (
    download,
)
from tests.helpers.download import PAYLOAD, Server, server, sha  # noqa: F401 (fixtures)


def test_a_killed_download_s_temporary_file_is_removed_by_the_next(
    server: Server, tmp_path: Path
) -> None:
    import subprocess
    import sys

    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    (tmp_path / f".file.bin.tmp-{dead.pid}").write_bytes(b"half a download")
    download(server.url("/file.bin"), tmp_path / "file.bin", sha(PAYLOAD), progress=False)
    assert os.listdir(tmp_path) == ["file.bin"]
