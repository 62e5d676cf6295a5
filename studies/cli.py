"""``prg-study``: build and analyse human-vs-robot handwriting user studies.

Examples
--------
``prg-study build conf/study/turing.yaml --human recordings/``
``prg-study build conf/study/readability.yaml --human recordings/ --set participants=40``
``prg-study build conf/study/turing.yaml --robot outputs/words/ --out /tmp/turing``

The program (its parser, ``build``, errors and exit codes) is :mod:`studies.program`; this entry
point adds ``analyze``, ``power`` and ``simulate`` from :mod:`studies.analysis.commands` when it
is installed. A mistake the user can fix (:class:`prg.errors.UsageError`) is one line,
``prg-study: error: <message>``, exit code 2; other :class:`prg.errors.PRGError` and an
:class:`OSError` about a file or the disk (see :func:`prg.commands.cli.os_error_message`) exit 1.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from prg.errors import UsageError
from prg.signals import deferred
from studies import program
from studies.program import Parser


def _add_unavailable(subparsers, reason: str) -> None:
    """Stand-ins for the analysis commands when :mod:`studies.analysis.commands` is missing."""
    for name in ("analyze", "power", "simulate"):
        p = subparsers.add_parser(name, help=f"(unavailable: {reason})", add_help=False)
        p.add_argument("rest", nargs=argparse.REMAINDER)

        def unavailable(args: argparse.Namespace, name: str = name) -> int:
            raise UsageError(f"{name} is not available: {reason}")

        p.set_defaults(func=unavailable)


def _add_analysis(subparsers) -> None:
    """``analyze``, ``power`` and ``simulate``, or stand-ins saying why they are unavailable."""
    # Held: a signal raised inside a C extension's import (numpy's) comes out as an ImportError,
    # which would read as "unavailable" instead of stopping the command.
    try:
        with deferred():
            from studies.analysis.commands import register as register_analysis
    except ImportError as err:
        _add_unavailable(subparsers, f"studies.analysis.commands cannot be imported ({err})")
    else:
        register_analysis(subparsers)


def make_parser() -> Parser:
    """The ``prg-study`` parser with every available sub-command."""
    return program.make_parser(_add_analysis)


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``prg-study``; returns the exit code (a signal exits with 128 + its number, see
    :func:`prg.commands.cli.handle_signals`)."""
    return program.main([_add_analysis], argv)


if __name__ == "__main__":
    sys.exit(main())
