"""Tests of ``prg.data``, one file per module: ``test_<module>.py``."""
