"""Thin Hydra entry points with one-line errors.

Every ``prg-*`` command is ``hydra_command(task, config_name, command)``. Before Hydra runs, the
command line is composed once against ``conf/`` so that an unknown config group, a typo in a key
or a malformed override is reported as one line with exit code 2 instead of Hydra's multi-line
message. Inside the task, :class:`prg.errors.PRGError` becomes ``<command>: error: <message>``
with its exit code (2 for usage errors, 1 for run-time failures); Ctrl-C exits with 130.
"""

from __future__ import annotations

import os
import sys
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


def compose_config(config_name: str, overrides: list[str]) -> Any:
    """Compose ``conf/<config_name>.yaml`` with overrides (no Hydra app, no output folder)."""
    from hydra import compose, initialize_config_dir

    with initialize_config_dir(config_dir=str(config_dir()), version_base="1.3"):
        return compose(config_name=config_name, overrides=overrides)


def _preflight(command: str, config_name: str, argv: list[str]) -> None:
    """Compose the command line once; report a bad override as one line (exit 2).

    Skipped when Hydra's own flags are used (``-m`` sweeps are expanded by Hydra, ``--cfg``,
    ``--help``, ``--config-name`` ... change what is composed).
    """
    if any(arg.startswith("-") for arg in argv):
        return
    overrides = [a for a in argv if not a.lstrip("+~").startswith(("hydra.", "hydra/"))]
    try:
        compose_config(config_name, overrides)
    except Exception as err:  # Hydra raises several types; all mean a bad override
        message = " ".join(str(err).split())
        cut = message.find("Set the environment variable HYDRA_FULL_ERROR")
        message = (message[:cut] if cut > 0 else message).strip()
        if "LexerNoViableAlt" in message or "mismatched input" in message:
            message += " (a value with spaces, commas or symbols needs Hydra quotes: 'key=\"...\"')"
        fail(command, message, 2)


def hydra_command(task: Callable[[Any], Any], config_name: str, command: str) -> Callable[[], None]:
    """Build a console-script ``main`` that runs ``task(cfg)`` under ``@hydra.main``."""
    import hydra

    @hydra.main(config_path=str(config_dir()), config_name=config_name, version_base="1.3")
    def _run(cfg) -> None:
        try:
            task(cfg)
        except PRGError as err:
            fail(command, str(err), err.exit_code)
        except KeyboardInterrupt:
            fail(command, "interrupted; nothing was written", 130)

    def main() -> None:
        _preflight(command, config_name, sys.argv[1:])
        _run()

    return main


__all__ = ["PRGError", "UsageError", "compose_config", "config_dir", "fail", "hydra_command"]
