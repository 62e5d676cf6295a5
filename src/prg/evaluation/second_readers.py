"""Second readers: a second, independently built classifier for each generated modality.

Coherence should not hang on one classifier. Beside the first classifiers of
:mod:`prg.evaluation.classifiers` (an MLP on the trajectory's coordinates, a CNN on the image's
pixels) every generated trajectory and image is read a second time, by a classifier that differs
from the first in its input and its architecture:

- ``traj_rendered`` (:class:`RenderedReader`): the trajectory drawn as the dataset draws its
  images (:func:`prg.data.preprocess.render_batch` with the prepared dataset's image settings)
  and read by the image CNN. The CNN never sees the order or the timing of the points, only the
  shape that a person would see. It needs no training of its own: the training images are the
  training trajectories drawn this way.
- ``image_knn`` (:class:`PixelNeighbours`): the class of the nearest training image in the space
  of the first :data:`COMPONENTS` principal components of the pixels (a plain nearest-neighbour
  rule, no learnt features).

:func:`ensure_second_readers` builds them next to the first classifiers, keeps the nearest
neighbours' reference set in ``<out_dir>/image_knn.npz`` (reused while the dataset's fingerprint
and the settings are unchanged, as the first classifiers are) and records each reader's accuracy
on the real test split in ``<out_dir>/metrics.json``.
"""

from __future__ import annotations

import io
import json
import logging
import os
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import torch
from sklearn.decomposition import PCA
from torch import nn

from prg.data.preprocess import render_batch
from prg.data.store import load_split
from prg.errors import UsageError
from prg.evaluation.classifiers import data_fingerprint, folded_accuracy, predict
from prg.files import read_json, write_bytes, write_json
from prg.models.modalities import IMAGE, LABEL, TRAJ

log = logging.getLogger(__name__)

FORMAT = "prg-pixel-neighbours"
FORMAT_VERSION = 1
COMPONENTS = 50
"""Principal components of the pixels the nearest-neighbour rule compares (measured on the real
test split of the synthetic dataset: 1-NN on the raw 784 pixels 0.876, on 50 components 0.882,
and four times faster)."""

QUERY_CHUNK = 256
"""Images compared with all references at once (a (256, N) distance matrix: 72 MB for the
70,308 training images)."""

NAMES: dict[str, str] = {TRAJ: "traj_rendered", IMAGE: "image_knn"}
"""Modality -> the name of its second reader (in reports and metric keys)."""


class Reader(NamedTuple):
    """A second reader of one modality: ``read`` maps a batch of that modality's model inputs
    (:func:`prg.evaluation.classifiers.to_input`) to class ids (N,); ``meta`` holds its test
    accuracies."""

    name: str
    read: Callable[[torch.Tensor], torch.Tensor]
    meta: dict[str, Any]


# -- trajectories: drawn, then read by the image classifier ------------------------------------


def render_settings(data_dir: str | os.PathLike) -> dict[str, float]:
    """``size``, ``stroke_width`` and ``margin`` with which the prepared dataset at ``data_dir``
    drew its images (its ``manifest.json``'s ``config.image``)."""
    path = Path(data_dir) / "manifest.json"
    manifest = read_json(path, "dataset manifest", f"no dataset manifest at {path}")
    try:
        image = manifest["config"]["image"]
        return {
            "size": int(image["size"]),
            "stroke_width": float(image["stroke_width"]),
            "margin": float(image["margin"]),
        }
    except (KeyError, TypeError, ValueError):
        raise UsageError(f"dataset manifest {path} has no config.image render settings") from None


class RenderedReader:
    """Reads trajectories by drawing them and classifying the drawing with an image classifier.

    Parameters
    ----------
    image_classifier : nn.Module
        Maps (N, 1, size, size) images in [0, 1] to logits.
    size, stroke_width, margin : see :func:`prg.data.preprocess.render`
        The prepared dataset's image settings (:func:`render_settings`).
    """

    def __init__(
        self, image_classifier: nn.Module, size: int, stroke_width: float, margin: float
    ) -> None:
        self.classifier = image_classifier
        self.settings = {"size": size, "stroke_width": stroke_width, "margin": margin}

    def images(self, traj: torch.Tensor | np.ndarray) -> torch.Tensor:
        """Trajectories (N, 200) -> images (N, 1, size, size) in [0, 1], quantised to 8 bits as
        the dataset stores them."""
        points = np.asarray(traj, dtype=np.float64).reshape(len(traj), -1, 2)
        ink = render_batch(points, **self.settings)
        return torch.from_numpy(np.round(ink * 255).astype(np.float32) / 255).unsqueeze(1)

    def __call__(self, traj: torch.Tensor) -> torch.Tensor:
        """Class ids (N,) of trajectories (N, 200)."""
        if len(traj) == 0:
            return torch.zeros(0, dtype=torch.long)
        return predict(self.classifier, self.images(traj))


# -- images: nearest training image ------------------------------------------------------------


class PixelNeighbours:
    """The class of the nearest reference image, compared on principal components of pixels.

    Parameters
    ----------
    mean : ndarray, shape (P,)
        Mean of the reference pixels (P = 28 * 28), ink in [0, 1].
    components : ndarray, shape (K, P)
        Principal axes (rows).
    references : ndarray, shape (N, K)
        The reference images' coordinates on those axes.
    labels : ndarray, shape (N,)
        Their classes.
    """

    def __init__(
        self, mean: np.ndarray, components: np.ndarray, references: np.ndarray, labels: np.ndarray
    ) -> None:
        self.mean = np.asarray(mean, dtype=np.float32)
        self.components = np.asarray(components, dtype=np.float32)
        self.references = np.asarray(references)
        self.labels = np.asarray(labels, dtype=np.int64)
        # the rule runs in torch: scikit-learn's OpenMP pool beside torch's slows every later
        # torch step of the evaluation (measured: the coherence part took twice as long)
        self._mean = torch.from_numpy(self.mean)
        self._axes = torch.from_numpy(self.components.T.copy())
        self._refs = torch.from_numpy(self.references.astype(np.float32))
        self._labels = torch.from_numpy(self.labels)

    @classmethod
    def fit(
        cls, images: np.ndarray, labels: np.ndarray, components: int = COMPONENTS, seed: int = 0
    ) -> PixelNeighbours:
        """Keep every image of ``images`` (uint8 (N, 28, 28) or floats in [0, 1]) as a reference,
        projected on its first ``components`` principal components (seeded)."""
        flat = _flat(images)
        if len(flat) == 0:
            raise UsageError("a nearest-neighbour reader needs reference images: none given")
        pca = PCA(min(components, *flat.shape), random_state=seed).fit(flat)
        # float16 coordinates halve the file; distances change in the 4th digit
        references = pca.transform(flat).astype(np.float16)
        return cls(pca.mean_, pca.components_, references, labels)

    def __call__(self, images: torch.Tensor | np.ndarray) -> torch.Tensor:
        """Class ids (N,) of images (N, 1, 28, 28) or (N, 28, 28) in [0, 1]."""
        if len(images) == 0:
            return torch.zeros(0, dtype=torch.long)
        flat = torch.as_tensor(np.asarray(images, dtype=np.float32)).reshape(len(images), -1)
        coords = (flat - self._mean) @ self._axes
        nearest = [torch.cdist(c, self._refs).argmin(1) for c in coords.split(QUERY_CHUNK)]
        return self._labels[torch.cat(nearest)]

    def save(self, path: str | os.PathLike, meta: Mapping[str, Any]) -> Path:
        """Write the reference set and plain-typed ``meta`` atomically (an ``.npz``)."""
        buffer = io.BytesIO()
        header = {"format": FORMAT, "version": FORMAT_VERSION, "meta": dict(meta)}
        np.savez(
            buffer,
            header=np.array(json.dumps(header)),
            mean=self.mean,
            components=self.components,
            references=self.references,
            labels=self.labels,
        )
        return write_bytes(Path(path), buffer.getvalue())

    @classmethod
    def load(cls, path: str | os.PathLike) -> tuple[PixelNeighbours, dict[str, Any]]:
        """Read a file written by :meth:`save`; returns (reader, meta).

        Raises
        ------
        UsageError
            If the file is missing, unreadable or not a reference set of this format.
        """
        path = Path(path)
        if not path.is_file():
            raise UsageError(f"nearest-neighbour file {path} does not exist")
        try:
            with np.load(path, allow_pickle=False) as arrays:
                header = json.loads(str(arrays["header"]))
                parts = {k: arrays[k] for k in ("mean", "components", "references", "labels")}
        except Exception as err:  # a damaged npz raises many types
            raise UsageError(f"nearest-neighbour file {path} is not readable ({err})") from None
        if not (
            isinstance(header, dict)
            and header.get("format") == FORMAT
            and header.get("version") == FORMAT_VERSION
            and isinstance(header.get("meta"), dict)
        ):
            raise UsageError(f"{path} is not a {FORMAT} file of version {FORMAT_VERSION}")
        return cls(**parts), header["meta"]


def _flat(images: np.ndarray) -> np.ndarray:
    images = np.asarray(images)
    flat = images.reshape(len(images), -1).astype(np.float32)
    return flat / 255 if images.dtype == np.uint8 else flat


# -- building them next to the first classifiers -----------------------------------------------


def _scores(pred: np.ndarray, labels: np.ndarray) -> dict[str, float]:
    return {
        "test_accuracy": float(np.mean(pred == labels)),
        "test_folded_accuracy": folded_accuracy(pred, labels),
    }


def ensure_second_readers(
    data_dir: str | os.PathLike,
    out_dir: str | os.PathLike,
    classifiers: Mapping[str, nn.Module],
    seed: int = 0,
) -> dict[str, Reader]:
    """The second reader of each classified modality (``traj``, ``image``), built or reused.

    ``<out_dir>/image_knn.npz`` is reused when its meta's data fingerprint
    (:func:`~prg.evaluation.classifiers.data_fingerprint`), components and seed are current;
    otherwise it is fitted on every training image (real and augmented) and scored on the real
    test images. The rendered-trajectory reader is scored on the real test trajectories each time
    (it follows the image classifier it borrows; half a second). ``<out_dir>/metrics.json`` (the
    first classifiers' accuracies, :func:`~prg.evaluation.classifiers.ensure_classifiers`) gets
    both readers' accuracies when they are missing or changed, and is left untouched otherwise.

    Parameters
    ----------
    data_dir : path
        The prepared dataset folder.
    out_dir : path
        The classifiers' folder.
    classifiers : mapping
        The first classifiers (modality -> model); the image CNN reads the drawn trajectories.
    seed : int
        Seed of the principal components.

    Returns
    -------
    dict
        Modality -> :class:`Reader`.
    """
    data_dir, out_dir = Path(data_dir), Path(out_dir)
    fingerprint = data_fingerprint(data_dir)
    test = load_split(data_dir / "test.npz")
    real = ~test["augmented"]
    labels = test[LABEL][real]

    rendered = RenderedReader(classifiers[IMAGE], **render_settings(data_dir))
    traj_meta = {
        "reader": "second: the image CNN on the drawn trajectory",
        **_scores(rendered(torch.as_tensor(test[TRAJ][real])).numpy(), labels),
    }

    path = out_dir / f"{NAMES[IMAGE]}.npz"
    settings = {"components": COMPONENTS, "seed": int(seed)}
    neighbours, image_meta = None, None
    if path.is_file():
        try:
            neighbours, image_meta = PixelNeighbours.load(path)
        except UsageError as err:
            log.warning("%s: refitting over it", err)
        if image_meta and (
            image_meta.get("data_fingerprint") != fingerprint
            or image_meta.get("settings") != settings
        ):
            neighbours, image_meta = None, None
    if neighbours is None:
        train = load_split(data_dir / "train.npz")
        neighbours = PixelNeighbours.fit(train[IMAGE], train[LABEL], COMPONENTS, seed)
        image_meta = {
            "reader": f"second: nearest training image, {COMPONENTS} principal components",
            "data_fingerprint": fingerprint,
            "settings": settings,
            "n_train": len(train[LABEL]),
            **_scores(neighbours(_flat(test[IMAGE][real])).numpy(), labels),
        }
        neighbours.save(path, image_meta)

    readers = {
        TRAJ: Reader(NAMES[TRAJ], rendered, traj_meta),
        IMAGE: Reader(NAMES[IMAGE], neighbours, image_meta),
    }
    _record(out_dir / "metrics.json", readers)
    return readers


def _record(path: Path, readers: Mapping[str, Reader]) -> None:
    """Add the readers' accuracies to the classifiers' metrics file when missing or changed."""
    metrics = read_json(path, "classifier metrics", "") if path.is_file() else {}
    if not isinstance(metrics, dict):
        metrics = {}
    new = {
        r.name: {k: r.meta[k] for k in ("test_accuracy", "test_folded_accuracy")}
        for r in readers.values()
    }
    if any(metrics.get(name) != value for name, value in new.items()):
        path.parent.mkdir(parents=True, exist_ok=True)
        write_json(path, {**metrics, **new})
