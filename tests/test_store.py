import numpy as np
import pytest

from prg.data.store import load_split, save_split
from prg.errors import UsageError


def _arrays(seed=0):
    rng = np.random.default_rng(seed)
    n = 7
    return {
        "traj": rng.normal(size=(n, 200)).astype(np.float32),
        "image": rng.integers(0, 256, size=(n, 28, 28), dtype=np.uint8),
        "label": rng.integers(0, 62, size=n),
        "writer": np.array([f"W{i}" for i in range(n)]),
        "augmented": np.zeros(n, dtype=bool),
        "parent": np.full(n, -1),
    }


def test_round_trip(tmp_path):
    arrays = _arrays()
    save_split(tmp_path / "train.npz", arrays)
    loaded = load_split(tmp_path / "train.npz")
    for key, value in arrays.items():
        np.testing.assert_array_equal(loaded[key], value)
    assert [p.name for p in tmp_path.iterdir()] == ["train.npz"]  # no temporary left


def test_same_arrays_give_identical_bytes(tmp_path):
    save_split(tmp_path / "a.npz", _arrays())
    save_split(tmp_path / "b.npz", _arrays())
    assert (tmp_path / "a.npz").read_bytes() == (tmp_path / "b.npz").read_bytes()


def test_missing_corrupt_and_incomplete_files_are_named(tmp_path):
    with pytest.raises(UsageError, match="does not exist"):
        load_split(tmp_path / "nope.npz")
    (tmp_path / "bad.npz").write_text("not a zip")
    with pytest.raises(UsageError, match="not a readable npz"):
        load_split(tmp_path / "bad.npz")
    np.savez(tmp_path / "partial.npz", traj=np.zeros(3))
    with pytest.raises(UsageError, match="lacks arrays"):
        load_split(tmp_path / "partial.npz")
