"""Helpers shared by the tests that were split out of tests/test_atomic.py."""

from __future__ import annotations

LIMIT = 256 * 1024  # bytes a process may write into one file during a test below
