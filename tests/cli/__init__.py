"""Command-line tests: each runs a ``prg-*`` console script (or ``python -m prg...``) in a
subprocess, as a user types it, and checks its exit code, its one-line errors and the files it
writes. Unit tests of the command modules themselves are under ``tests/prg/commands/``."""
