"""Tests of ``prg.data.sigma_lognormal``, one file per module: ``test_<module>.py``."""
