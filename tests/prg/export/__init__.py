"""Tests of ``prg.export``, one file per module: ``test_<module>.py``."""
