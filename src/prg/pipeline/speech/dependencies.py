"""The optional speech dependencies (``pip install prg[speech]``): what to install when one is
missing, and one-line errors from them."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from prg.errors import UsageError
from prg.signals import deferred

INSTALL = "pip install prg[speech]"


def first_line(err: BaseException) -> str:
    """``Type: first line of the message`` of an exception from a third-party library."""
    lines = str(err).strip().splitlines()
    return f"{type(err).__name__}: {lines[0]}" if lines else type(err).__name__


@contextmanager
def needs(dependency: str, backend: str) -> Iterator[None]:
    """Imports in the block are ``backend``'s optional ``dependency``: an :class:`ImportError`
    becomes a :class:`UsageError` saying what to install. Signals are held meanwhile: one raised
    inside a C extension's import comes out as an ImportError and would read as "not installed"."""
    try:
        with deferred():
            yield
    except ImportError:
        raise UsageError(
            f"speech backend {backend!r} needs {dependency}, not installed: {INSTALL}"
        ) from None
