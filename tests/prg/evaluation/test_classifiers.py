"""Coherence classifiers: training, determinism, files, reuse per dataset, folded accuracy."""

from __future__ import annotations

import json
import re
import shutil

import numpy as np
import pytest
import torch

from prg.alphabet import ALPHABET, NUM_CLASSES
from prg.data.store import load_split
from prg.errors import UsageError
from prg.evaluation import classifiers as clf

QUICK = {"epochs": 2, "batch_size": 64, "lr": 2e-3, "seed": 0}


@pytest.fixture(scope="module")
def splits(small_dataset):
    root = small_dataset / "prepared" / "synthetic"
    return {s: load_split(root / f"{s}.npz") for s in ("train", "val", "test")}


@pytest.fixture
def data_dir(small_dataset, tmp_path):
    """A private copy of the small prepared dataset (its manifest may be edited)."""
    return shutil.copytree(small_dataset / "prepared" / "synthetic", tmp_path / "data")


def _train(modality, splits, **overrides):
    settings = {**QUICK, **overrides}
    return clf.train_classifier(
        modality, splits["train"], splits["val"], **settings, progress=False
    )


def _x(modality, arrays):
    return clf.to_input(modality, arrays[modality])


def test_inputs_follow_the_models_conventions(splits):
    train = splits["train"]
    image = clf.to_input("image", train["image"][:5])
    assert image.shape == (5, 1, 28, 28) and image.dtype == torch.float32
    np.testing.assert_allclose(image[:, 0].numpy() * 255, train["image"][:5], atol=1e-4)
    traj = clf.to_input("traj", train["traj"][:5])
    assert traj.shape == (5, 200) and traj.dtype == torch.float32
    for name, model in clf.CLASSIFIERS.items():
        assert model()(clf.to_input(name, train[name][:3])).shape == (3, NUM_CLASSES)
    with pytest.raises(UsageError, match="'label'"):
        clf.to_input("label", train["label"])


@pytest.mark.parametrize("modality", clf.MODALITIES)
def test_training_beats_chance_by_far(splits, modality):
    model, history = _train(modality, splits, epochs=10, batch_size=32)
    train = splits["train"]
    acc = clf.accuracy(model, _x(modality, train), train["label"])
    assert acc > 0.5 > 30 / NUM_CLASSES  # chance is 1/62
    assert len(history["val_accuracy"]) == 10
    assert history["best_val_accuracy"] == max(history["val_accuracy"])
    assert not model.training


def test_best_validation_epoch_is_kept(splits):
    model, history = _train("traj", splits, epochs=4)
    val = splits["val"]
    assert clf.accuracy(model, _x("traj", val), val["label"]) == history["best_val_accuracy"]


def test_same_seed_same_weights_and_predictions(splits):
    state = torch.random.get_rng_state()
    a, _ = _train("image", splits)
    b, _ = _train("image", splits)
    c, _ = _train("image", splits, seed=1)
    assert torch.equal(torch.random.get_rng_state(), state)  # caller's RNG untouched
    for key, value in a.state_dict().items():
        assert torch.equal(value, b.state_dict()[key]), key
    assert not all(torch.equal(v, c.state_dict()[k]) for k, v in a.state_dict().items())
    x = _x("image", splits["test"])
    assert torch.equal(clf.predict(a, x), clf.predict(b, x))


def test_the_weights_do_not_depend_on_the_callers_thread_count(splits):
    # the judge of every seed and session: the same classifier however many threads torch has
    threads = torch.get_num_threads()
    try:
        torch.set_num_threads(1)
        a, _ = _train("image", splits)
        torch.set_num_threads(2)
        b, _ = _train("image", splits)
        assert torch.get_num_threads() == 2  # the caller's setting is given back
    finally:
        torch.set_num_threads(threads)
    for key, value in a.state_dict().items():
        assert torch.equal(value, b.state_dict()[key]), key


def test_predict_batches_give_the_same_classes(splits):
    model, _ = _train("traj", splits, epochs=1)
    x = _x("traj", splits["test"])
    with torch.no_grad():
        whole = model(x).argmax(-1)
    assert torch.equal(clf.predict(model, x, batch_size=7), whole)
    assert clf.predict(model, x[:0]).shape == (0,)


@pytest.mark.parametrize("modality", clf.MODALITIES)
def test_save_load_round_trip(splits, tmp_path, modality):
    model, _ = _train(modality, splits, epochs=1)
    meta = {"test_accuracy": 0.5, "cfg": dict(QUICK), "note": "x"}
    path = clf.save_classifier(tmp_path / f"{modality}.pt", model, modality, meta)
    assert [p.name for p in tmp_path.iterdir()] == [path.name]  # no temporary left
    payload = torch.load(path, weights_only=True)  # plain types only
    assert payload["modality"] == modality
    loaded, loaded_meta = clf.load_classifier(path)
    assert isinstance(loaded, clf.CLASSIFIERS[modality])
    assert loaded_meta == {**meta, "modality": modality}
    x = _x(modality, splits["test"])
    assert torch.equal(clf.predict(loaded, x), clf.predict(model, x))


def test_missing_corrupt_and_foreign_files_raise_usage_errors(splits, tmp_path):
    missing = tmp_path / "missing.pt"
    with pytest.raises(UsageError, match=re.escape(f"{missing} does not exist")):
        clf.load_classifier(missing)
    garbage = tmp_path / "garbage.pt"
    garbage.write_bytes(b"not a torch file at all")
    model, _ = _train("traj", splits, epochs=1)
    good = clf.save_classifier(tmp_path / "good.pt", model, "traj", {})
    truncated = tmp_path / "truncated.pt"
    truncated.write_bytes(good.read_bytes()[:1000])
    foreign = tmp_path / "foreign.pt"
    torch.save({"weights": torch.zeros(3)}, foreign)
    mismatched = tmp_path / "mismatched.pt"
    torch.save({**torch.load(good, weights_only=True), "modality": "image"}, mismatched)
    for path in (garbage, truncated, foreign, mismatched):
        with pytest.raises(UsageError) as err:
            clf.load_classifier(path)
        message = str(err.value)
        assert str(path) in message and "\n" not in message, message


def test_ensure_classifiers_trains_once_then_reuses(data_dir, tmp_path, monkeypatch):
    out = tmp_path / "classifiers"
    models = clf.ensure_classifiers(data_dir, out, QUICK, progress=False)
    assert set(models) == set(clf.MODALITIES)
    test = load_split(data_dir / "test.npz")
    metrics = json.loads((out / "metrics.json").read_text())
    stamps = {}
    for modality in clf.MODALITIES:
        _, meta = clf.load_classifier(out / f"{modality}.pt")
        assert meta["data_fingerprint"] == clf.data_fingerprint(data_dir)
        assert meta["cfg"] == QUICK and meta["epochs"] == QUICK["epochs"]
        assert meta["n_train"] == len(load_split(data_dir / "train.npz")["label"])
        pred = clf.predict(models[modality], _x(modality, test)).numpy()
        assert meta["test_accuracy"] == pytest.approx(np.mean(pred == test["label"]))
        assert meta["test_folded_accuracy"] == pytest.approx(
            clf.folded_accuracy(pred, test["label"])
        )
        assert metrics[modality]["test_accuracy"] == meta["test_accuracy"]
        stamps[modality] = (out / f"{modality}.pt").stat().st_mtime_ns

    def no_training(*args, **kwargs):
        raise AssertionError("retrained a classifier that should have been reused")

    monkeypatch.setattr(clf, "train_classifier", no_training)
    again = clf.ensure_classifiers(data_dir, out, dict(QUICK), progress=False)
    for modality in clf.MODALITIES:
        assert (out / f"{modality}.pt").stat().st_mtime_ns == stamps[modality]
        x = _x(modality, test)
        assert torch.equal(clf.predict(again[modality], x), clf.predict(models[modality], x))


def test_classifier_files_are_the_same_bytes_whatever_the_training_took(data_dir, tmp_path):
    # two trainings on the same data and settings: the same files (a DVC output that stays
    # put), the time each took in metrics.json only, kept there when a file is reused
    first, second = tmp_path / "a", tmp_path / "b"
    clf.ensure_classifiers(data_dir, first, QUICK, progress=False)
    clf.ensure_classifiers(data_dir, second, QUICK, progress=False)
    for modality in clf.MODALITIES:
        a, b = (d / f"{modality}.pt" for d in (first, second))
        assert a.read_bytes() == b.read_bytes()
        assert "train_seconds" not in clf.load_classifier(a)[1]
    metrics = json.loads((first / "metrics.json").read_text())
    assert all(metrics[m]["train_seconds"] > 0 for m in clf.MODALITIES)
    (first / "metrics.json").unlink()  # reused files, no record of their training: no time
    clf.ensure_classifiers(data_dir, first, QUICK, progress=False)
    rewritten = json.loads((first / "metrics.json").read_text())
    assert all("train_seconds" not in rewritten[m] for m in clf.MODALITIES)
    assert rewritten["traj"]["test_accuracy"] == metrics["traj"]["test_accuracy"]


def test_ensure_classifiers_retrains_when_the_data_or_cfg_change(data_dir, tmp_path):
    out = tmp_path / "classifiers"
    clf.ensure_classifiers(data_dir, out, QUICK, progress=False)
    old = clf.data_fingerprint(data_dir)
    provenance = data_dir / "provenance.json"
    provenance.write_text(json.dumps({"code_version": {"git_commit": "0" * 40}}))
    assert clf.data_fingerprint(data_dir) == old  # the code version alone: the same data
    manifest = json.loads((data_dir / "manifest.json").read_text())
    manifest["input"]["sha256"] = "f" * 64  # different input data
    (data_dir / "manifest.json").write_text(json.dumps(manifest))
    new = clf.data_fingerprint(data_dir)
    assert new != old
    clf.ensure_classifiers(data_dir, out, QUICK, progress=False)
    for modality in clf.MODALITIES:
        assert clf.load_classifier(out / f"{modality}.pt")[1]["data_fingerprint"] == new
    clf.ensure_classifiers(data_dir, out, {**QUICK, "epochs": 1}, progress=False)
    for modality in clf.MODALITIES:
        assert clf.load_classifier(out / f"{modality}.pt")[1]["cfg"]["epochs"] == 1
    assert json.loads((out / "metrics.json").read_text())["data_fingerprint"] == new
    (out / "traj.pt").write_bytes(b"damaged")  # a damaged file is retrained over
    clf.ensure_classifiers(data_dir, out, {**QUICK, "epochs": 1}, progress=False)
    assert clf.load_classifier(out / "traj.pt")[1]["data_fingerprint"] == new
    assert sorted(p.name for p in out.iterdir()) == ["image.pt", "metrics.json", "traj.pt"]


def test_ensure_classifiers_rejects_bad_inputs(data_dir, tmp_path):
    with pytest.raises(UsageError, match="keys"):
        clf.ensure_classifiers(data_dir, tmp_path, {"epochs": 1}, progress=False)
    with pytest.raises(UsageError, match="not numeric"):
        clf.ensure_classifiers(data_dir, tmp_path, {**QUICK, "lr": "fast"}, progress=False)
    with pytest.raises(UsageError, match="epochs"):
        clf.ensure_classifiers(data_dir, tmp_path, {**QUICK, "epochs": 0}, progress=False)
    with pytest.raises(UsageError, match="manifest"):
        clf.ensure_classifiers(tmp_path / "nowhere", tmp_path, QUICK, progress=False)


def test_shape_twin_groups_are_disjoint_classes():
    members = [ch for group in clf.SHAPE_TWINS for ch in group]
    assert len(members) == len(set(members)) and set(members) <= set(ALPHABET)
    for group in clf.SHAPE_TWINS:
        assert len(group) >= 2


def test_folded_accuracy_is_at_least_exact_and_equal_without_twins():
    rng = np.random.default_rng(0)
    labels = rng.integers(0, NUM_CLASSES, 500)
    pred = np.where(rng.random(500) < 0.5, labels, rng.integers(0, NUM_CLASSES, 500))
    exact = float(np.mean(pred == labels))
    assert clf.folded_accuracy(pred, labels) >= exact
    twin = {ALPHABET.index(ch) for group in clf.SHAPE_TWINS for ch in group}
    keep = np.array([p not in twin and t not in twin for p, t in zip(pred, labels)])
    assert clf.folded_accuracy(pred[keep], labels[keep]) == np.mean(pred[keep] == labels[keep])
    # a confusion inside a group counts as right, one across groups does not
    for group in clf.SHAPE_TWINS:
        a, b = (ALPHABET.index(ch) for ch in group[:2])
        assert clf.folded_accuracy([a, b], [b, a]) == 1.0
    a, b = (ALPHABET.index(group[0]) for group in clf.SHAPE_TWINS[:2])
    assert clf.folded_accuracy([a], [b]) == 0.0
    assert clf.folded_accuracy(torch.tensor([a]), torch.tensor([a])) == 1.0


def test_confusion_matrix_counts_pairs():
    labels = np.array([0, 0, 1, 2, 2, 2])
    pred = np.array([0, 1, 1, 2, 0, 2])
    cm = clf.confusion_matrix(pred, labels, n=3)
    assert cm.sum() == len(labels) and np.trace(cm) == np.sum(pred == labels)
    for t, p in zip(labels, pred):
        assert cm[t, p] >= 1
