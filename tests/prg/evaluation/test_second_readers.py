"""Second readers: the drawn-trajectory reader sees the dataset's own images, the pixel
nearest-neighbour rule learns, its file round-trips and is reused per dataset."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
import torch

from prg.alphabet import NUM_CLASSES
from prg.data.store import load_split
from prg.errors import UsageError
from prg.evaluation import classifiers as clf
from prg.evaluation import second_readers as sr

QUICK = {"epochs": 2, "batch_size": 64, "lr": 2e-3, "seed": 0}


@pytest.fixture(scope="module")
def root(small_dataset):
    return small_dataset / "prepared" / "synthetic"


@pytest.fixture(scope="module")
def splits(root):
    return {s: load_split(root / f"{s}.npz") for s in ("train", "val", "test")}


@pytest.fixture(scope="module")
def image_cnn(splits):
    model, _ = clf.train_classifier(
        "image", splits["train"], splits["val"], **QUICK, progress=False
    )
    return model


def test_drawn_trajectories_are_the_datasets_images(root, splits):
    reader = sr.RenderedReader(None, **sr.render_settings(root))
    test = splits["test"]
    drawn = reader.images(torch.as_tensor(test["traj"][:40]))
    assert drawn.shape == (40, 1, 28, 28)
    np.testing.assert_array_equal(np.round(drawn[:, 0].numpy() * 255), test["image"][:40])


def test_the_drawn_trajectory_reader_reads_as_the_image_classifier(root, splits, image_cnn):
    reader = sr.RenderedReader(image_cnn, **sr.render_settings(root))
    val = splits["val"]
    from_traj = reader(torch.as_tensor(val["traj"]))
    from_image = clf.predict(image_cnn, clf.to_input("image", val["image"]))
    assert torch.equal(from_traj, from_image)
    assert reader(torch.zeros(0, 200)).shape == (0,)


def test_pixel_neighbours_learn(splits):
    train, val = splits["train"], splits["val"]
    reader = sr.PixelNeighbours.fit(train["image"], train["label"], components=30, seed=0)
    assert reader.references.shape == (len(train["label"]), 30)
    on_train = reader(clf.to_input("image", train["image"])).numpy()
    on_val = reader(clf.to_input("image", val["image"])).numpy()
    assert np.mean(on_train == train["label"]) > 0.95  # its own references (float16 coords)
    assert np.mean(on_val == val["label"]) > 10 / NUM_CLASSES  # other writers; chance is 1/62
    assert reader(np.zeros((0, 28, 28))).shape == (0,)


def test_pixel_neighbours_file_round_trip_and_bad_files(splits, tmp_path):
    train, val = splits["train"], splits["val"]
    reader = sr.PixelNeighbours.fit(train["image"][:300], train["label"][:300], components=10)
    path = reader.save(tmp_path / "knn.npz", {"note": "x"})
    again, meta = sr.PixelNeighbours.load(path)
    assert meta == {"note": "x"}
    images = clf.to_input("image", val["image"])
    assert torch.equal(again(images), reader(images))
    with pytest.raises(UsageError, match="does not exist"):
        sr.PixelNeighbours.load(tmp_path / "none.npz")
    (tmp_path / "bad.npz").write_bytes(b"not a zip")
    with pytest.raises(UsageError, match="not readable"):
        sr.PixelNeighbours.load(tmp_path / "bad.npz")


def test_ensure_second_readers_fits_once_then_reuses(root, tmp_path, image_cnn, monkeypatch):
    data = shutil.copytree(root, tmp_path / "data")
    out = tmp_path / "classifiers"
    (out).mkdir()
    (out / "metrics.json").write_text(json.dumps({"traj": {"test_accuracy": 0.5}}))
    readers = sr.ensure_second_readers(data, out, {"image": image_cnn}, seed=0)
    assert set(readers) == {"traj", "image"}
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["traj"] == {"test_accuracy": 0.5}  # the first classifiers' entries are kept
    for reader in readers.values():
        assert metrics[reader.name]["test_accuracy"] == reader.meta["test_accuracy"]
        assert 0 <= reader.meta["test_accuracy"] <= reader.meta["test_folded_accuracy"] <= 1
    stamp = (out / "image_knn.npz").stat().st_mtime_ns, (out / "metrics.json").stat().st_mtime_ns

    def no_fit(*args, **kwargs):
        raise AssertionError("refitted although nothing changed")

    monkeypatch.setattr(sr.PixelNeighbours, "fit", no_fit)
    again = sr.ensure_second_readers(data, out, {"image": image_cnn}, seed=0)
    assert again["image"].meta == readers["image"].meta
    now = (out / "image_knn.npz").stat().st_mtime_ns, (out / "metrics.json").stat().st_mtime_ns
    assert now == stamp  # neither file rewritten
    monkeypatch.undo()

    manifest = json.loads((data / "manifest.json").read_text())
    manifest["counts"] = {"changed": 1}
    (data / "manifest.json").write_text(json.dumps(manifest))
    refit = sr.ensure_second_readers(data, out, {"image": image_cnn}, seed=0)
    assert refit["image"].meta["data_fingerprint"] == clf.data_fingerprint(data)
    assert refit["image"].meta["data_fingerprint"] != readers["image"].meta["data_fingerprint"]
