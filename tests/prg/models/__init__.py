"""Tests of ``prg.models``, one file per module: ``test_<module>.py``."""
