"""Tests of ``prg.commands``, one file per module: ``test_<module>.py``."""
