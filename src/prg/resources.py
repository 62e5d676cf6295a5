"""Where the project's own files are: the ``conf/`` folder of configs and robot descriptions."""

from __future__ import annotations

import os
from pathlib import Path


def config_dir() -> Path:
    """The repository's ``conf/`` folder (``PRG_CONF_DIR`` overrides it)."""
    env = os.environ.get("PRG_CONF_DIR")
    return Path(env) if env else Path(__file__).resolve().parents[2] / "conf"
