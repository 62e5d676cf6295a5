"""Tests of ``prg.evaluation``, one file per module: ``test_<module>.py``."""
