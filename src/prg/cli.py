"""Thin Hydra entry points with one-line errors.

Every ``prg-*`` command is ``hydra_command(task, config_name, command)``. Before Hydra runs, the
command line is composed once against ``conf/`` so that an unknown config group, a typo in a key
or a malformed override is reported as one line with exit code 2 instead of Hydra's multi-line
message; Hydra's log folder (``paths.log_dir``) is checked there too. Inside the task,
:class:`prg.errors.PRGError` becomes ``<command>: error: <message>`` with its exit code (2 for
usage errors, 1 for run-time failures); an :class:`OSError` about a file or the disk (no space,
read-only, permission, I/O error) is a run-time failure naming the path (exit 1); Ctrl-C exits
with 130. Any other exception is a bug and keeps its traceback.

Tasks call :func:`check_output` on every output path before they start working, so a path that
cannot be written is a usage error (exit 2) before anything is computed or written.
"""

from __future__ import annotations

import errno
import os
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

from prg.errors import PRGError, UsageError


def config_dir() -> Path:
    """The repository's ``conf/`` folder (``PRG_CONF_DIR`` overrides it)."""
    env = os.environ.get("PRG_CONF_DIR")
    return Path(env) if env else Path(__file__).resolve().parents[2] / "conf"


def fail(command: str, message: str, code: int) -> None:
    """Print one line to stderr and exit."""
    print(f"{command}: error: {message}", file=sys.stderr)
    sys.exit(code)


def check_output(path: str | os.PathLike, key: str, *, folder: bool = True) -> Path:
    """``path`` if an output folder (or, ``folder=False``, a file) can be written there.

    The nearest existing folder on the way is probed by creating and removing an empty folder in
    it, which also catches what file modes do not tell root (a read-only or pseudo file system
    such as ``/sys``). Nothing is left behind.

    Raises
    ------
    UsageError
        Naming ``key`` and the path: it exists but is of the wrong kind, a file stands where a
        folder must be, or the folder refuses new entries.
    """
    path = Path(path)
    kind = "a folder" if folder else "a regular file"
    if path.exists() and (path.is_dir() != folder or not (folder or path.is_file())):
        raise UsageError(f"{key} {path}: exists and is not {kind}")
    existing = path if folder else path.parent
    while not existing.exists():  # also False below a regular file
        existing = existing.parent
    if not existing.is_dir():
        raise UsageError(f"{key} {path}: {existing} is a file, not a folder")
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".prg-probe-", dir=existing))
    except OSError as err:
        raise UsageError(f"{key} {path}: cannot write in {existing} ({err.strerror})") from None
    return path


# OSErrors that are about the machine, not the code, even without a file name.
_ENVIRONMENT_ERRNOS = {
    errno.ENOSPC,
    errno.EDQUOT,
    errno.EROFS,
    errno.EIO,
    errno.EACCES,
    errno.EPERM,
}


def os_error_message(err: OSError) -> str | None:
    """One line for an OSError about a named file or the disk; None for any other OSError."""
    if err.filename is None and err.errno not in _ENVIRONMENT_ERRNOS:
        return None
    reason = err.strerror or str(err)
    if err.filename is None:
        return reason
    names = f"{err.filename} -> {err.filename2}" if err.filename2 else str(err.filename)
    return f"{names}: {reason}"


def compose_config(config_name: str, overrides: list[str], hydra_config: bool = False) -> Any:
    """Compose ``conf/<config_name>.yaml`` with overrides (no Hydra app, no output folder);
    ``hydra_config``: keep the ``hydra`` node."""
    from hydra import compose, initialize_config_dir

    with initialize_config_dir(config_dir=str(config_dir()), version_base="1.3"):
        return compose(
            config_name=config_name, overrides=overrides, return_hydra_config=hydra_config
        )


def _preflight(command: str, config_name: str, argv: list[str]) -> None:
    """Compose the command line once; report a bad override as one line (exit 2).

    Also refuses a Hydra log folder (``hydra.run.dir``, under ``paths.log_dir``) that cannot be
    created, which Hydra itself would report with a traceback. Skipped when Hydra's own flags
    are used (``-m`` sweeps are expanded by Hydra, ``--cfg``, ``--help``, ``--config-name`` ...
    change what is composed).
    """
    if any(arg.startswith("-") for arg in argv):
        return
    overrides = [
        a
        for a in argv
        if a.startswith("hydra.run.dir=") or not a.lstrip("+~").startswith(("hydra.", "hydra/"))
    ]
    try:
        run_dir = compose_config(config_name, overrides, hydra_config=True).hydra.run.dir
    except Exception as err:  # Hydra raises several types; all mean a bad override
        message = " ".join(str(err).split())
        cut = message.find("Set the environment variable HYDRA_FULL_ERROR")
        message = (message[:cut] if cut > 0 else message).strip()
        if "LexerNoViableAlt" in message or "mismatched input" in message:
            message += " (a value with spaces, commas or symbols needs Hydra quotes: 'key=\"...\"')"
        fail(command, message, 2)
    try:
        check_output(run_dir, "Hydra's log folder (paths.log_dir)")
    except UsageError as err:
        fail(command, str(err), 2)


def hydra_command(task: Callable[[Any], Any], config_name: str, command: str) -> Callable[[], None]:
    """Build a console-script ``main`` that runs ``task(cfg)`` under ``@hydra.main``."""
    import hydra

    @hydra.main(config_path=str(config_dir()), config_name=config_name, version_base="1.3")
    def _run(cfg) -> None:
        try:
            task(cfg)
        except PRGError as err:
            fail(command, str(err), err.exit_code)
        except OSError as err:
            message = os_error_message(err)
            if message is None:
                raise
            fail(command, message, 1)
        except KeyboardInterrupt:
            fail(command, "interrupted; nothing was written", 130)

    def main() -> None:
        _preflight(command, config_name, sys.argv[1:])
        _run()

    return main


__all__ = [
    "PRGError",
    "UsageError",
    "check_output",
    "compose_config",
    "config_dir",
    "fail",
    "hydra_command",
    "os_error_message",
]
