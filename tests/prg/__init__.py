"""Tests of ``prg``, one file per module: ``test_<module>.py``."""
