"""Tests of ``studies.analysis.stats``, one file per module: ``test_<module>.py``."""
