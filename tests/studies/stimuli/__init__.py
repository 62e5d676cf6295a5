"""Tests of ``studies.stimuli``, one file per module: ``test_<module>.py``."""
