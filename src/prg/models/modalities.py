"""The modalities of a handwritten letter: one record each, read by every part that handles them.

The paper names them by letter: T, the pen trajectory; S, the symbol (the class label); I, the
grey image of the letter. Each :class:`Modality` holds what the rest of the project reads about
one of them: its name (the key of batches, split files and configs), its letter, the shape and
dtype of one sample as the models take it and as ``prg-prepare`` stores it, the conversion from
a stored split to model inputs, the appendix networks that encode and decode it
(:mod:`prg.models.components`), its likelihood (:mod:`prg.models.likelihoods`), and its kind
(how its samples are drawn in figures and classified for coherence).

:data:`MODALITIES` lists them in the paper's order (T, S, I), the order of subset names
(``"S,I"``), of metric keys and of report columns. Code that handles any modality reads the
registry; code about one by its meaning (the class label every split holds, the trajectory the
robot writes) names it with :data:`TRAJ`, :data:`LABEL` or :data:`IMAGE`. A model family's own
equations (the CVAE is T given S) keep their modalities in the family's module.

Adding a modality: write its encoder and decoder, add its record here (a likelihood and a kind
the project knows, or a new one where :mod:`prg.models.likelihoods`, the figures and the
classifiers handle kinds) and list it in a model config's ``modalities``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np
import torch
from torch import nn

from prg.models.components import (
    IMAGE_SHAPE,
    TRAJ_DIM,
    ImageDecoder,
    ImageEncoder,
    LabelDecoder,
    LabelEncoder,
    TrajectoryDecoder,
    TrajectoryEncoder,
)

TRAJ, LABEL, IMAGE = "traj", "label", "image"

LIKELIHOODS = ("gaussian", "categorical", "bernoulli")
"""Likelihood families :class:`prg.models.likelihoods.Likelihoods` evaluates."""

KINDS = ("points", "class", "pixels")
"""How a modality's samples look: ``points``, a flat sequence of 2-D points ``x1, y1, x2, ...``
(drawn as a line, classified by an MLP); ``class``, an index into the alphabet (shown as text,
read by its most probable class); ``pixels``, a grey image (drawn as one, classified by a CNN)."""


@dataclass(frozen=True)
class ShapeOption:
    """The ``prg-prepare`` option that sets a modality's stored shape.

    Attributes
    ----------
    key
        the option (``data.preprocess.n_points``).
    value
        the option's value that gives a split array of a shape (``(N, 200)`` -> 100); for a
        shape no value gives, the part of the shape to show instead.
    """

    key: str
    value: Callable[[tuple[int, ...]], Any]


@dataclass(frozen=True)
class Modality:
    """One modality: what the data, the models, the evaluation and the figures read about it.

    name : key of batches, split files and configs (``"traj"``).
    letter : the paper's letter (``"T"``).
    plural : what its samples are called in figure titles (``"trajectories"``).
    kind : one of :data:`KINDS`.
    shape, dtype : one sample as the models take it (a batch adds a leading dimension).
    stored_shape, stored_dtype : one sample as ``prg-prepare`` stores it (:mod:`prg.data.store`).
    prepare : stored tensor -> model input, for a batch or a single sample.
    likelihood : one of :data:`LIKELIHOODS`, of the decoder's output.
    encoder, decoder : the appendix networks, built as ``encoder(latent_dim)``.
    shape_option : the ``prg-prepare`` option that sets ``stored_shape`` (None: fixed).
    """

    name: str
    letter: str
    plural: str
    kind: str
    shape: tuple[int, ...]
    dtype: torch.dtype
    stored_shape: tuple[int, ...]
    stored_dtype: type[np.generic]
    prepare: Callable[[torch.Tensor], torch.Tensor]
    likelihood: str
    encoder: type[nn.Module]
    decoder: type[nn.Module]
    shape_option: ShapeOption | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS or self.likelihood not in LIKELIHOODS:
            raise ValueError(f"modality {self.name}: unknown kind or likelihood")

    def load(self, array: np.ndarray | torch.Tensor) -> torch.Tensor:
        """A stored split array as a tensor of :attr:`stored_dtype` (no copy when it already is
        one): compact, for holding a split in memory; :attr:`prepare` makes model inputs."""
        return torch.from_numpy(np.ascontiguousarray(array, dtype=self.stored_dtype))

    def to_tensor(self, array: np.ndarray | torch.Tensor) -> torch.Tensor:
        """A stored split array as model inputs (:meth:`load`, then :attr:`prepare`)."""
        return self.prepare(self.load(array))


def _as_stored(x: torch.Tensor) -> torch.Tensor:
    return x


def _ink_to_pixels(x: torch.Tensor) -> torch.Tensor:
    """uint8 ink 0..255, (..., 28, 28) -> float pixels (..., 1, 28, 28) in [0, 1]."""
    return x.unsqueeze(-3).float().div(255.0)


def _n_points(shape: tuple[int, ...]) -> Any:
    """(N, 2 n_points) -> n_points; another shape as it is."""
    return shape[1] // 2 if len(shape) == 2 else shape


def _image_size(shape: tuple[int, ...]) -> Any:
    """(N, size, size) -> size; another shape without N."""
    return shape[1] if len(shape) == 3 and shape[1] == shape[2] else shape[1:]


_RECORDS = (
    Modality(
        name=TRAJ,
        letter="T",
        plural="trajectories",
        kind="points",
        shape=(TRAJ_DIM,),
        dtype=torch.float32,
        stored_shape=(TRAJ_DIM,),
        stored_dtype=np.float32,
        prepare=_as_stored,
        likelihood="gaussian",
        encoder=TrajectoryEncoder,
        decoder=TrajectoryDecoder,
        shape_option=ShapeOption("data.preprocess.n_points", _n_points),
    ),
    Modality(
        name=LABEL,
        letter="S",
        plural="labels",
        kind="class",
        shape=(),
        dtype=torch.int64,
        stored_shape=(),
        stored_dtype=np.int64,
        prepare=_as_stored,
        likelihood="categorical",
        encoder=LabelEncoder,
        decoder=LabelDecoder,
    ),
    Modality(
        name=IMAGE,
        letter="I",
        plural="images",
        kind="pixels",
        shape=IMAGE_SHAPE,
        dtype=torch.float32,
        stored_shape=IMAGE_SHAPE[1:],
        stored_dtype=np.uint8,
        prepare=_ink_to_pixels,
        likelihood="bernoulli",
        encoder=ImageEncoder,
        decoder=ImageDecoder,
        shape_option=ShapeOption("data.image.size", _image_size),
    ),
)

MODALITIES: Mapping[str, Modality] = MappingProxyType({m.name: m for m in _RECORDS})
"""Name -> record, in the paper's order T, S, I."""

NAMES: tuple[str, ...] = tuple(MODALITIES)
"""The modalities' names in the paper's order: ``("traj", "label", "image")``."""

LETTER: Mapping[str, str] = MappingProxyType({m.name: m.letter for m in _RECORDS})
"""Name -> the paper's letter: ``traj`` T, ``label`` S, ``image`` I."""


def in_order(names: Iterable[str]) -> tuple[str, ...]:
    """The known modalities among ``names``, in the paper's order."""
    given = set(names)
    return tuple(m for m in NAMES if m in given)


def letters(names: Iterable[str], sep: str = "") -> str:
    """The paper's letters of ``names`` in the paper's order: ``("image", "label")`` -> ``"SI"``."""
    return sep.join(LETTER[m] for m in in_order(names))
