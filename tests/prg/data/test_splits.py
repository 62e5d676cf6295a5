"""Tests of ``prg.data.splits``."""

import pytest

from prg.data.splits import split_writers
from prg.errors import UsageError

WRITERS = [f"W{i:02d}" for i in range(60)]


def test_every_writer_in_exactly_one_split_with_the_asked_fractions():
    out = split_writers(WRITERS * 2, {"train": 0.7, "val": 0.15, "test": 0.15}, seed=0)
    assert sorted(out["train"] + out["val"] + out["test"]) == WRITERS
    assert (len(out["train"]), len(out["val"]), len(out["test"])) == (42, 9, 9)
    assert not set(out["train"]) & set(out["val"]) | set(out["train"]) & set(out["test"])


def test_assignment_depends_on_seed_not_on_order():
    fr = {"train": 0.8, "val": 0.1, "test": 0.1}
    a = split_writers(WRITERS, fr, seed=1)
    assert a == split_writers(list(reversed(WRITERS)), fr, seed=1)
    assert a != split_writers(WRITERS, fr, seed=2)


def test_small_fraction_still_gets_a_writer():
    out = split_writers(["a", "b", "c", "d"], {"train": 0.9, "val": 0.05, "test": 0.05}, seed=0)
    assert len(out["val"]) == len(out["test"]) == 1


@pytest.mark.parametrize(
    "writers, fractions, match",
    [
        (WRITERS, {"train": 0.7, "val": 0.2}, "sum to 1"),
        (WRITERS, {"train": 1.2, "val": -0.2}, ">= 0"),
        (WRITERS, {"train": 0.8, "dev": 0.2}, "unknown split"),
        (["a", "b"], {"train": 0.6, "val": 0.2, "test": 0.2}, "cannot make"),
    ],
)
def test_bad_splits_are_refused(writers, fractions, match):
    with pytest.raises(UsageError, match=match):
        split_writers(writers, fractions, seed=0)
