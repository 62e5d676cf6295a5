"""Independent classifiers that score the cross-modal coherence of generated samples.

One classifier per generated modality, trained on the prepared dataset and never on a model's
output: :class:`TrajectoryClassifier` (an MLP on the 200 normalised coordinates) and
:class:`ImageClassifier` (a small CNN on 28x28 images). A generated trajectory or image is
*coherent* with its condition when the classifier recovers the condition's class.

:func:`ensure_classifiers` trains both once per dataset and keeps them in
``<out_dir>/<modality>.pt`` with their test accuracy; a saved classifier is reused while the
dataset's fingerprint (:func:`data_fingerprint`) and the training config are unchanged.

Exact accuracy is the headline number. Normalised letters lose their size, so some upper- and
lowercase letters (and digits) are the same shape; :data:`SHAPE_TWINS` groups them and
:func:`folded_accuracy` counts a prediction within the true class's group as right.
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import io
import json
import logging
import os
import time
from collections.abc import Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn
from tqdm.auto import tqdm

from prg.alphabet import ALPHABET, NUM_CLASSES
from prg.data.store import load_split
from prg.errors import UsageError
from prg.evaluation.settings import DEFAULT_CFG  # exported here too (the settings' defaults)
from prg.files import read_json, write_bytes, write_json
from prg.models.modalities import LABEL
from prg.models.modalities import MODALITIES as REGISTRY

log = logging.getLogger(__name__)

FORMAT = "prg-classifier"
FORMAT_VERSION = 1
CFG_KEYS: tuple[str, ...] = ("epochs", "batch_size", "lr", "seed")

SHAPE_TWINS: tuple[str, ...] = ("0Oo", "Cc", "Iil", "Pp", "Ss", "Vv", "Ww", "Xx", "Zz")
"""Groups of classes that are the same shape once size and position are normalised away.

Measured with the default classifiers on the real test split of the synthetic dataset (1,116
samples, 18 per class): confusions between the two classes of a pair, both directions
together (out of 36 samples), trajectory / image classifier::

    X-x 10/9   Z-z 7/11   C-c 8/6   I-l 4/10   O-o 5/8   S-s 6/7   V-v 5/8
    i-l  8/5   W-w 5/7    I-i 3/4   0-O 4/3    P-p 2/2   (0-o 3/0)

A pair is a twin when *each* classifier confuses it at least twice; a group joins pairs that
share a class (``i``, ``I`` and ``l`` are all a plain vertical stroke: the single-stroke ``i``
has no dot). The next pairs are h-k 4/1 (a real error, not a size effect), U-u, 1-T and F-P 1/1;
every other pair is confused at most once by each classifier. ``1`` is no twin of ``I``/``l``:
its flag keeps it apart (no such confusion). The 20 classes in groups hold 70 of the 84
trajectory errors and 80 of the 97 image errors. Re-measure when the data change (e.g. UJI).
"""


def _fold_table(groups: tuple[str, ...] = SHAPE_TWINS) -> np.ndarray:
    """Class id -> id of its group's first member (itself when in no group)."""
    table = np.arange(NUM_CLASSES)
    for group in groups:
        ids = [ALPHABET.index(ch) for ch in group]
        table[ids] = ids[0]
    return table


FOLD: np.ndarray = _fold_table()
"""``FOLD[c]`` is the representative class of ``c``'s shape-twin group."""


# -- models -----------------------------------------------------------------------------------


class TrajectoryClassifier(nn.Module):
    """MLP on a normalised trajectory: (B, 200) -> logits (B, 62)."""

    def __init__(
        self,
        in_dim: int = 200,
        hidden: tuple[int, ...] = (512, 256),
        num_classes: int = NUM_CLASSES,
        dropout: float = 0.2,
    ):
        super().__init__()
        layers: list[nn.Module] = []
        for width in hidden:
            layers += [nn.Linear(in_dim, width), nn.LeakyReLU(0.1), nn.Dropout(dropout)]
            in_dim = width
        layers.append(nn.Linear(in_dim, num_classes))
        self.net = nn.Sequential(*layers)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.net(x)


class ImageClassifier(nn.Module):
    """Small CNN on an image in [0, 1]: (B, 1, 28, 28) -> logits (B, 62).

    Two stride-2 convolutions (28 -> 14 -> 7) instead of convolution + max-pooling: four times
    cheaper to train on a CPU (13 s instead of 53 s per epoch of the full dataset on 2 cores),
    within about a point of its test accuracy.
    """

    def __init__(
        self,
        channels: tuple[int, int] = (32, 64),
        hidden: int = 256,
        num_classes: int = NUM_CLASSES,
        dropout: float = 0.3,
    ):
        super().__init__()
        c1, c2 = channels
        self.features = nn.Sequential(
            nn.Conv2d(1, c1, 3, stride=2, padding=1),  # 14x14
            nn.LeakyReLU(0.1),
            nn.Conv2d(c1, c2, 3, stride=2, padding=1),  # 7x7
            nn.LeakyReLU(0.1),
        )
        self.head = nn.Sequential(
            nn.Flatten(),
            nn.Linear(c2 * 7 * 7, hidden),
            nn.LeakyReLU(0.1),
            nn.Dropout(dropout),
            nn.Linear(hidden, num_classes),
        )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.head(self.features(x))


NETWORKS: dict[str, type[nn.Module]] = {"points": TrajectoryClassifier, "pixels": ImageClassifier}
"""The classifier network of each kind of modality (:data:`prg.models.modalities.KINDS`; a class label
needs none: its most probable class is read directly)."""

CLASSIFIERS: dict[str, type[nn.Module]] = {
    m.name: NETWORKS[m.kind] for m in REGISTRY.values() if m.kind in NETWORKS
}
"""Modality -> its classifier: ``traj`` :class:`TrajectoryClassifier`, ``image``
:class:`ImageClassifier`."""

MODALITIES: tuple[str, ...] = tuple(CLASSIFIERS)
"""The modalities with a classifier, in the paper's order: ``("traj", "image")``."""


def _check_modality(modality: str) -> None:
    if modality not in CLASSIFIERS:
        raise UsageError(f"no classifier for modality {modality!r}: accepted are {MODALITIES}")


def to_input(modality: str, array: np.ndarray | torch.Tensor) -> torch.Tensor:
    """Split array -> classifier input, the models' input of the modality
    (:meth:`prg.models.modalities.Modality.to_tensor`).

    ``traj`` float (N, 200) -> float32 (N, 200); ``image`` uint8 (N, 28, 28) -> float32
    (N, 1, 28, 28) in [0, 1] (ink / 255).
    """
    _check_modality(modality)
    return REGISTRY[modality].to_tensor(array)


# -- prediction and scores --------------------------------------------------------------------


@torch.no_grad()
def predict(model: nn.Module, x: torch.Tensor, batch_size: int = 1024) -> torch.Tensor:
    """Class ids (N,) of inputs ``x`` (already through :func:`to_input`), in eval mode."""
    was_training = model.training
    model.eval()
    try:
        out = [model(x[i : i + batch_size]).argmax(-1) for i in range(0, len(x), batch_size)]
    finally:
        model.train(was_training)
    return torch.cat(out) if out else torch.zeros(0, dtype=torch.long)


def accuracy(model: nn.Module, x: torch.Tensor, labels: np.ndarray | torch.Tensor) -> float:
    """Fraction of ``x`` whose predicted class equals ``labels``."""
    pred = predict(model, x)
    return float((pred == torch.as_tensor(np.asarray(labels))).float().mean())


def folded_accuracy(pred: np.ndarray | torch.Tensor, labels: np.ndarray | torch.Tensor) -> float:
    """Accuracy that counts a prediction in the true class's :data:`SHAPE_TWINS` group as right."""
    pred, labels = np.asarray(pred), np.asarray(labels)
    return float(np.mean(FOLD[pred] == FOLD[labels]))


def confusion_matrix(
    pred: np.ndarray | torch.Tensor, labels: np.ndarray | torch.Tensor, n: int = NUM_CLASSES
) -> np.ndarray:
    """Counts (n, n): row = true class, column = predicted class."""
    pred, labels = np.asarray(pred, dtype=np.int64), np.asarray(labels, dtype=np.int64)
    return np.bincount(labels * n + pred, minlength=n * n).reshape(n, n)


# -- training ---------------------------------------------------------------------------------


@contextmanager
def one_thread():
    """Torch on one thread inside, the caller's thread count restored after.

    A classifier is trained on one thread: the CNN's weights depend on how many threads share
    its sums (on the demo data the image classifier's test accuracy is 0.9131 trained on one
    thread, 0.9104 on two), and every seed, run and session must be judged by the same one. It
    costs the image classifier about 40 s of one core."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(threads)


def train_classifier(
    modality: str,
    train_arrays: Mapping[str, np.ndarray],
    val_arrays: Mapping[str, np.ndarray],
    *,
    epochs: int,
    batch_size: int,
    lr: float,
    seed: int,
    progress: bool = True,
) -> tuple[nn.Module, dict[str, Any]]:
    """Train a classifier of ``modality``; keep the weights of the best validation epoch.

    Adam with a cosine learning-rate decay to zero over all steps, cross-entropy loss. The run
    is deterministic for a seed, whatever the caller's thread count (it trains on one thread,
    :func:`one_thread`; initialisation and dropout from ``torch.manual_seed(seed)`` inside a
    forked RNG, so the caller's global RNG state is untouched; the shuffle from its own
    ``torch.Generator``).

    Parameters
    ----------
    modality : one of :data:`MODALITIES` ("traj", "image")
    train_arrays, val_arrays : mapping
        Split arrays (:func:`prg.data.store.load_split`) with ``modality`` and ``label``.
    epochs, batch_size : int
    lr : float
        Peak learning rate.
    seed : int
    progress : bool
        Show a progress bar over training steps.

    Returns
    -------
    model : nn.Module
        In eval mode, with the best-validation-accuracy weights.
    history : dict
        ``train_loss`` and ``val_accuracy`` per epoch, ``best_epoch`` (0-based),
        ``best_val_accuracy``, ``seconds`` (wall time).
    """
    _check_modality(modality)
    if not isinstance(epochs, int) or epochs < 1:
        raise UsageError(f"classifier epochs must be an integer >= 1, got {epochs!r}")
    if not isinstance(batch_size, int) or batch_size < 1:
        raise UsageError(f"classifier batch_size must be an integer >= 1, got {batch_size!r}")
    if not lr > 0:
        raise UsageError(f"classifier lr must be > 0, got {lr!r}")
    x = to_input(modality, train_arrays[modality])
    y = torch.as_tensor(np.asarray(train_arrays[LABEL], dtype=np.int64))
    x_val = to_input(modality, val_arrays[modality])
    y_val = np.asarray(val_arrays[LABEL])
    if len(x) == 0 or len(x_val) == 0:
        raise UsageError("a classifier needs training and validation samples: a split is empty")
    start = time.perf_counter()
    history: dict[str, Any] = {"train_loss": [], "val_accuracy": []}
    with one_thread(), torch.random.fork_rng(devices=[]):
        torch.manual_seed(seed)
        model = CLASSIFIERS[modality]()
        shuffle = torch.Generator().manual_seed(seed)
        optimiser = torch.optim.Adam(model.parameters(), lr=lr)
        steps_per_epoch = -(-len(x) // batch_size)
        schedule = torch.optim.lr_scheduler.CosineAnnealingLR(optimiser, epochs * steps_per_epoch)
        loss_fn = nn.CrossEntropyLoss()
        best_acc, best_state, best_epoch = -1.0, None, -1
        bar = tqdm(
            total=epochs * steps_per_epoch,
            desc=f"classifier {modality}",
            disable=not progress,
            leave=False,
        )
        for epoch in range(epochs):
            model.train()
            order = torch.randperm(len(x), generator=shuffle)
            total = 0.0
            for i in range(0, len(x), batch_size):
                index = order[i : i + batch_size]
                loss = loss_fn(model(x[index]), y[index])
                optimiser.zero_grad(set_to_none=True)
                loss.backward()
                optimiser.step()
                schedule.step()
                total += loss.item() * len(index)
                bar.update()
            val_acc = accuracy(model, x_val, y_val)
            history["train_loss"].append(total / len(x))
            history["val_accuracy"].append(val_acc)
            bar.set_postfix(epoch=epoch + 1, loss=f"{total / len(x):.3f}", val_acc=f"{val_acc:.3f}")
            if val_acc > best_acc:
                best_acc, best_epoch = val_acc, epoch
                best_state = copy.deepcopy(model.state_dict())
        bar.close()
    model.load_state_dict(best_state)
    model.eval()
    history.update(
        best_epoch=best_epoch, best_val_accuracy=best_acc, seconds=time.perf_counter() - start
    )
    return model, history


# -- files ------------------------------------------------------------------------------------


def _recorded_metrics(path: Path) -> dict:
    """The classifiers' ``metrics.json`` as written before, or ``{}`` (missing or unreadable:
    only the training times it holds are read from it)."""
    try:
        recorded = read_json(path, "classifier metrics")
    except UsageError:
        return {}
    return recorded if isinstance(recorded, dict) else {}


def _train_seconds(recorded, meta: dict) -> dict:
    """``{"train_seconds": s}`` from the metrics a training wrote (or, for a file saved before
    the time moved out of it, from its ``meta``); empty when neither has it."""
    for source in (recorded, meta):
        if isinstance(source, dict) and isinstance(source.get("train_seconds"), int | float):
            return {"train_seconds": source["train_seconds"]}
    return {}


def save_classifier(
    path: str | os.PathLike, model: nn.Module, modality: str, meta: Mapping[str, Any]
) -> Path:
    """Write a classifier (weights and plain-typed ``meta``) atomically; returns the path.

    The file holds only plain containers, numbers, strings and tensors, so it loads with
    ``torch.load(weights_only=True)``. Written to a temporary name in the same folder, then
    renamed.
    """
    _check_modality(modality)
    path = Path(path)
    payload = {
        "format": FORMAT,
        "version": FORMAT_VERSION,
        "modality": modality,
        "meta": json.loads(json.dumps(dict(meta))),  # plain types only (fails loudly otherwise)
        "state_dict": {k: v.detach().cpu().clone() for k, v in model.state_dict().items()},
    }
    buffer = io.BytesIO()  # torch.save reports a failed file write as a RuntimeError
    torch.save(payload, buffer)
    return write_bytes(path, buffer.getvalue())


def load_classifier(path: str | os.PathLike) -> tuple[nn.Module, dict[str, Any]]:
    """Read a file written by :func:`save_classifier`; returns (model in eval mode, meta).

    Raises
    ------
    UsageError
        If the file is missing, unreadable, or not a classifier of a known modality.
    """
    path = Path(path)
    if not path.is_file():
        raise UsageError(f"classifier file {path} does not exist")
    try:
        payload = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as err:  # torch.load raises many types on a damaged file
        reason = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise UsageError(
            f"classifier file {path} is not a readable torch file ({reason})"
        ) from None
    if not (
        isinstance(payload, dict)
        and payload.get("format") == FORMAT
        and payload.get("version") == FORMAT_VERSION
        and payload.get("modality") in CLASSIFIERS
        and isinstance(payload.get("meta"), dict)
        and isinstance(payload.get("state_dict"), dict)
    ):
        raise UsageError(
            f"classifier file {path} is not a {FORMAT} file of version {FORMAT_VERSION}"
        )
    model = CLASSIFIERS[payload["modality"]]()
    try:
        model.load_state_dict(payload["state_dict"])
    except RuntimeError:
        raise UsageError(
            f"classifier file {path} has weights that do not fit the {payload['modality']} "
            "classifier: delete it to retrain"
        ) from None
    model.eval()
    return model, {**payload["meta"], "modality": payload["modality"]}


# -- one classifier per dataset ---------------------------------------------------------------


def data_fingerprint(data_dir: str | os.PathLike) -> str:
    """SHA-256 of a prepared dataset's ``manifest.json``.

    The manifest records the input checksum, the full data config, the writer split and the
    per-class counts, so it changes whenever the data do; the code version is not in it
    (``provenance.json`` beside it), because a new commit that rebuilds the same data should not
    force retraining.
    """
    path = Path(data_dir) / "manifest.json"
    missing = f"no dataset manifest at {path}: run `prg-prepare` first"
    manifest = read_json(path, "dataset manifest", missing)
    if not isinstance(manifest, dict):
        raise UsageError(f"dataset manifest {path} is not a JSON object")
    return hashlib.sha256(json.dumps(manifest, sort_keys=True).encode()).hexdigest()


def _check_cfg(cfg: Any) -> dict[str, Any]:
    cfg = dataclasses.asdict(cfg) if dataclasses.is_dataclass(cfg) else dict(cfg)
    if set(cfg) != set(CFG_KEYS):
        raise UsageError(
            f"classifier config has keys {sorted(cfg)}: expected exactly {sorted(CFG_KEYS)}"
        )
    types = {"epochs": int, "batch_size": int, "lr": float, "seed": int}
    try:
        return {k: types[k](cfg[k]) for k in CFG_KEYS}
    except (TypeError, ValueError):
        raise UsageError(
            f"classifier config {cfg} is not numeric: epochs, batch_size and seed are integers, "
            "lr a number"
        ) from None


def _reusable(
    path: Path, modality: str, fingerprint: str, settings: dict[str, Any]
) -> tuple[nn.Module | None, dict[str, Any] | None]:
    """The saved classifier at ``path`` if it was trained on these data with these settings."""
    if not path.is_file():
        return None, None
    try:
        model, meta = load_classifier(path)
    except UsageError as err:
        log.warning("%s: retraining over it", err)
        return None, None
    if (
        meta.get("modality") == modality
        and meta.get("data_fingerprint") == fingerprint
        and meta.get("cfg") == settings
        and meta.get("shape_twins") == list(SHAPE_TWINS)
    ):
        return model, meta
    return None, None


def ensure_classifiers(
    data_dir: str | os.PathLike,
    out_dir: str | os.PathLike,
    cfg: Any = None,
    progress: bool = True,
) -> dict[str, nn.Module]:
    """Load, or train and save, the classifiers (:data:`MODALITIES`: traj and image) of a
    prepared dataset.

    ``<out_dir>/<modality>.pt`` is reused when its meta's data fingerprint equals
    :func:`data_fingerprint` of ``data_dir``, its cfg equals ``cfg`` and its twin table equals
    :data:`SHAPE_TWINS` (its folded accuracy is then current); otherwise (also when the file is
    damaged, with a logged warning) the classifier is trained on the train split (val selects
    the epoch), scored on the real (non-augmented) samples of the test split and saved.
    ``<out_dir>/metrics.json`` gets the accuracies of both when either was trained (or when it
    is missing).

    Parameters
    ----------
    data_dir : path
        A prepared dataset folder (``<paths.data_dir>/prepared/<name>``).
    out_dir : path
        Where the classifier files and ``metrics.json`` go.
    cfg : mapping or :class:`~prg.evaluation.settings.ClassifierSettings`, optional
        ``epochs``, ``batch_size``, ``lr``, ``seed`` (:func:`train_classifier`), used for both
        modalities. Default :data:`DEFAULT_CFG`.
    progress : bool

    Returns
    -------
    dict
        Modality -> classifier in eval mode.
    """
    data_dir, out_dir = Path(data_dir), Path(out_dir)
    settings = _check_cfg(DEFAULT_CFG if cfg is None else cfg)
    fingerprint = data_fingerprint(data_dir)
    splits: dict[str, dict[str, np.ndarray]] = {}

    def split(name: str) -> dict[str, np.ndarray]:
        if name not in splits:
            splits[name] = load_split(data_dir / f"{name}.npz")
        return splits[name]

    models: dict[str, nn.Module] = {}
    metrics: dict[str, Any] = {}
    trained = False
    # the training time is a run fact: kept in metrics.json, not in the classifier file, whose
    # bytes then depend on the data and the settings only (a DVC output that stays put)
    seconds = _recorded_metrics(out_dir / "metrics.json")
    for modality in MODALITIES:
        path = out_dir / f"{modality}.pt"
        model, meta = _reusable(path, modality, fingerprint, settings)
        if model is None:
            model, history = train_classifier(
                modality, split("train"), split("val"), **settings, progress=progress
            )
            test = split("test")
            real = ~test["augmented"]
            pred = predict(model, to_input(modality, test[modality][real])).numpy()
            labels = test[LABEL][real]
            meta = {
                "modality": modality,
                "data_fingerprint": fingerprint,
                "cfg": settings,
                "test_accuracy": float(np.mean(pred == labels)),
                "test_folded_accuracy": folded_accuracy(pred, labels),
                "val_accuracy": history["best_val_accuracy"],
                "best_epoch": history["best_epoch"],
                "n_train": len(split("train")[LABEL]),
                "n_test": int(real.sum()),
                "epochs": settings["epochs"],
                "shape_twins": list(SHAPE_TWINS),
            }
            seconds[modality] = {"train_seconds": round(history["seconds"], 2)}
            save_classifier(path, model, modality, meta)
            trained = True
        models[modality] = model
        metrics[modality] = {
            **{k: meta[k] for k in ("test_accuracy", "test_folded_accuracy", "val_accuracy")},
            **_train_seconds(seconds.get(modality), meta),
        }
    # rewritten only when something changed: a reuse (e.g. by prg-evaluate after the DVC
    # `classifiers` stage) must not touch another stage's output
    if trained or not (out_dir / "metrics.json").is_file():
        out_dir.mkdir(parents=True, exist_ok=True)
        write_json(out_dir / "metrics.json", {**metrics, "data_fingerprint": fingerprint})
    return models
