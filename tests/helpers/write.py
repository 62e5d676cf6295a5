"""Helpers shared by the tests that were split out of tests/test_write.py."""

from pathlib import Path

import pytest

# what prg-write leaves in its folder (with the default record=true)
WORD_OUTPUTS = {"word.json", "word.png", "word.svg", "dmp_rollout.csv", "motion.csv", "word.rrd"}


@pytest.fixture(scope="module")
def checkpoint(untrained_muse_checkpoint) -> Path:
    return untrained_muse_checkpoint


WORD_FOLDER = r"ab_cd-\d{8}-\d{6}(-\d+)?"  # <text>-<YYYYmmdd-HHMMSS>, -2 ... when taken
