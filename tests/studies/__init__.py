"""Tests of ``studies``, one file per module: ``test_<module>.py``."""
