"""Tests of ``prg.sim``, one file per module: ``test_<module>.py``."""
