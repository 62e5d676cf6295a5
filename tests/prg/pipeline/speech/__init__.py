"""Tests of ``prg.pipeline.speech``, one file per module: ``test_<module>.py``."""
