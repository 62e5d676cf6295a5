"""Tests of ``prg.tracking``, one file per module: ``test_<module>.py``."""
