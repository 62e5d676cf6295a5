"""Exceptions that reach the user as one line.

Every command catches :class:`PRGError` at its edge and prints ``<command>: error: <message>``
with no traceback. :class:`UsageError` (bad input the user can fix: a value, a path, a file)
exits with code 2; any other :class:`PRGError` (the work failed at run time) exits with code 1.
Messages name the culprit and what is accepted.
"""

from __future__ import annotations

import argparse


class PRGError(Exception):
    """A failure the user should see as one line (exit code 1)."""

    exit_code = 1


class UsageError(PRGError, ValueError):
    """Bad input given by the user: a config value, a path, a file's contents (exit code 2)."""

    exit_code = 2


class DataFormatError(UsageError):
    """A data file that does not follow its format; names the file and the line."""

    def __init__(self, message: str, *, path: str | None = None, line: int | None = None):
        where = ""
        if path is not None:
            where = f"{path}"
            if line is not None:
                where += f", line {line}"
            where += ": "
        elif line is not None:
            where = f"line {line}: "
        super().__init__(where + message)
        self.path = path
        self.line = line


class UncertainWordError(UsageError):
    """Speech rescoring heard no lexicon word clearly enough (``speech.min_lead``): ask the
    speaker to repeat. ``candidates`` holds the best lexicon words scored, with their scores,
    best first (:attr:`prg.pipeline.speech.Transcript.candidates`)."""

    def __init__(self, message: str, candidates: tuple[tuple[str, float], ...]):
        super().__init__(message)
        self.candidates = candidates


class DownloadError(PRGError):
    """A download failed or its checksum did not match; nothing was written."""


class SettingsError(UsageError):
    """A settings value a library dataclass refuses; names the field (``lift_cm``), not the config
    path: the command layer that read the value adds its path with :meth:`under`
    (``motion.lift_cm``), so the library does not know the layout of the config tree."""

    def __init__(self, field: str, problem: str):
        super().__init__(f"{field} {problem}")
        self.field = field
        self.problem = problem

    def under(self, prefix: str | None) -> SettingsError:
        """The same error with ``prefix.`` before the field (unchanged for an empty prefix)."""
        return SettingsError(f"{prefix}.{self.field}" if prefix else self.field, self.problem)


class UsageParser(argparse.ArgumentParser):
    """An argparse parser whose errors (a missing or malformed option) raise :class:`UsageError`,
    so the command's edge prints them as its one line, instead of argparse's usage block."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise UsageError(message)
