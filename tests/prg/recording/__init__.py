"""Tests of ``prg.recording``, one file per module: ``test_<module>.py``."""
