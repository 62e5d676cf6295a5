"""Tests of ``studies.analysis``, one file per module: ``test_<module>.py``."""
