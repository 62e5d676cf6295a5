"""Exceptions that reach the user as one line.

Every command catches :class:`PRGError` at its edge and prints ``<command>: error: <message>``
with no traceback. :class:`UsageError` (bad input the user can fix: a value, a path, a file)
exits with code 2; any other :class:`PRGError` (the work failed at run time) exits with code 1.
Messages name the culprit and what is accepted.
"""

from __future__ import annotations


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


class DownloadError(PRGError):
    """A download failed or its checksum did not match; nothing was written."""
