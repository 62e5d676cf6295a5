"""Tests of ``prg.pipeline.dmp``, one file per module: ``test_<module>.py``."""
