"""The project's own files: where the ``conf/`` folder of configs and robot descriptions is, and
which commit of the code runs and on which CPU (recorded with every dataset, run and report)."""

from __future__ import annotations

import os
import platform
import subprocess
from pathlib import Path


def config_dir() -> Path:
    """The repository's ``conf/`` folder (``PRG_CONF_DIR`` overrides it)."""
    env = os.environ.get("PRG_CONF_DIR")
    return Path(env) if env else Path(__file__).resolve().parents[2] / "conf"


def git_commit() -> str:
    """Commit of the code that runs (``+dirty`` when src/ or conf/ have uncommitted changes),
    or ``"unknown"`` outside a git checkout."""
    where = Path(__file__).resolve().parent

    def git(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run(["git", *args], cwd=where, capture_output=True, text=True, timeout=5)

    try:
        head = git("rev-parse", "HEAD")
        if head.returncode != 0:
            return "unknown"
        top = git("rev-parse", "--show-toplevel").stdout.strip()
        dirty = git("status", "--porcelain", "--", f"{top}/src", f"{top}/conf").stdout.strip()
        return head.stdout.strip() + ("+dirty" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def project_path(path: str | os.PathLike, root: str | os.PathLike) -> str:
    """``path`` as the reports name a project file: relative to the project root ``root`` when
    it lies inside it (``models/muse/model.ckpt``, the same on every machine and checkout),
    absolute otherwise. ``..`` is folded first; a root or path reached through a symbolic link
    is also compared with the links resolved."""
    absolute = Path(os.path.abspath(path))
    for inside, top in ((absolute, Path(os.path.abspath(root))), (None, None)):
        if inside is None:  # the same with links resolved
            inside, top = absolute.resolve(), Path(root).resolve()
        try:
            return inside.relative_to(top).as_posix() or "."
        except ValueError:
            continue
    return str(absolute)


def cpu_name() -> str:
    """The CPU's model name (``/proc/cpuinfo``), with its core count."""
    name = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                name = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{name or platform.processor() or platform.machine()} ({os.cpu_count()} cores)"
