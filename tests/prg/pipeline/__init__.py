"""Tests of ``prg.pipeline``, one file per module: ``test_<module>.py``."""
