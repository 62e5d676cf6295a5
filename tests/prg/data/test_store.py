"""Tests of ``prg.data.store`` (moved from the suite on: the dataset build as a function: contents,
writer-disjointness, reproducibility)."""

import json

import numpy as np
import pytest

from prg.data.store import load_split, save_split
from prg.errors import UsageError


def _splits(data_dir, name="synthetic"):
    root = data_dir / "prepared" / name
    return {s: load_split(root / f"{s}.npz") for s in ("train", "val", "test")}, root


def test_prepared_dataset_has_modalities_in_the_documented_format(small_dataset):
    splits, root = _splits(small_dataset)
    for arrays in splits.values():
        n = len(arrays["label"])
        assert arrays["traj"].shape == (n, 200) and arrays["traj"].dtype == np.float32
        assert arrays["image"].shape == (n, 28, 28) and arrays["image"].dtype == np.uint8
        assert arrays["label"].min() >= 0 and arrays["label"].max() <= 61
        pts = arrays["traj"].reshape(n, 100, 2)
        assert np.allclose(np.abs(pts).max(axis=(1, 2)), 1.0, atol=1e-5)  # normalised
        assert (arrays["image"].reshape(n, -1).max(axis=1) > 200).all()  # ink in every image
    manifest = json.loads((root / "manifest.json").read_text())
    assert manifest["source"] == "synthetic" and manifest["input"]["kind"] == "synthetic"
    assert manifest["counts"]["train"]["augmented"] == 3 * 62


def test_splits_are_writer_disjoint_and_only_train_is_augmented(small_dataset):
    splits, _ = _splits(small_dataset)
    writers = {s: set(a["writer"]) for s, a in splits.items()}
    assert not writers["train"] & writers["val"]
    assert not writers["train"] & writers["test"]
    assert not writers["val"] & writers["test"]
    assert not splits["val"]["augmented"].any() and not splits["test"]["augmented"].any()
    train = splits["train"]
    children = np.flatnonzero(train["augmented"])
    parents = train["parent"][children]
    assert (~train["augmented"][parents]).all()
    assert (train["label"][parents] == train["label"][children]).all()


def _case_twins(a: str, b: str) -> bool:
    """Letters whose upper and lower case have the same shape once size is normalised away."""
    twins = [
        set("oO0"),
        set("cC"),
        set("sS"),
        set("vV"),
        set("wW"),
        set("xX"),
        set("zZ"),
        set("uU"),
        set("pP"),
        set("kK"),
        set("yY"),
        set("lI1"),
        set("9gq"),
    ]
    return a == b or any(a in t and b in t for t in twins)


def test_augmented_letters_are_still_recognisable(small_dataset):
    """1-nearest-neighbour fitted on the originals labels >= 90 % of augmented samples right
    (62 classes; case twins such as o/O, whose normalised shapes coincide, count as right)."""
    from prg.alphabet import ALPHABET

    train = load_split(small_dataset / "prepared/synthetic/train.npz")
    originals = ~train["augmented"]
    ref, ref_labels = train["traj"][originals], train["label"][originals]
    queries, truth = train["traj"][train["augmented"]], train["label"][train["augmented"]]
    dist = ((queries[:, None, :] - ref[None, :, :]) ** 2).sum(-1)
    predicted = ref_labels[dist.argmin(axis=1)]
    right = [_case_twins(ALPHABET[p], ALPHABET[t]) for p, t in zip(predicted, truth)]
    assert np.mean(right) >= 0.9, np.mean(right)


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
