"""Tests of ``prg.pipeline.speech.backends``, one file per module: ``test_<module>.py``."""
