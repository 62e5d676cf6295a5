"""The training writers' letters a checkpoint keeps: the components of the hands that generated
words are written in (:mod:`prg.pipeline.hands`).

Only the originals are kept (a split's ``augmented`` False): the sigma-lognormal augmentation
moves letters off the writers' manifold. ``PRGModule.on_save_checkpoint`` stores the training
split's as ``checkpoint["hands"]`` (tensors and strings: checkpoints are read with
``weights_only=True``); :func:`prg.models.checkpoint.load_model` returns them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import torch

#: The checkpoint entry that holds the bank.
CHECKPOINT_KEY = "hands"


@dataclass(frozen=True)
class HandBank:
    """The real letters a model writes from: the training split's originals.

    Attributes
    ----------
    traj : ndarray, shape (N, 200), float32
        Normalised trajectories (``prg.data.store`` layout).
    label : ndarray, shape (N,), int64
    writer : ndarray, shape (N,), int64
        Index into ``writers``.
    writers : tuple of str
        The writers' ids.
    """

    traj: np.ndarray
    label: np.ndarray
    writer: np.ndarray
    writers: tuple[str, ...]

    @classmethod
    def from_split(cls, arrays: dict[str, np.ndarray]) -> HandBank:
        """The originals (``augmented`` False) of a split's arrays."""
        keep = ~np.asarray(arrays["augmented"], dtype=bool)
        names, index = np.unique(
            np.asarray(arrays["writer"])[keep].astype(str), return_inverse=True
        )
        return cls(
            traj=np.asarray(arrays["traj"], dtype=np.float32)[keep],
            label=np.asarray(arrays["label"], dtype=np.int64)[keep],
            writer=index.astype(np.int64),
            writers=tuple(str(n) for n in names),
        )

    def to_checkpoint(self) -> dict[str, Any]:
        """Tensors and strings only (checkpoints are read with ``weights_only=True``)."""
        return {
            "traj": torch.from_numpy(self.traj),
            "label": torch.from_numpy(self.label),
            "writer": torch.from_numpy(self.writer),
            "writers": list(self.writers),
        }

    @classmethod
    def from_checkpoint(cls, entry: dict[str, Any]) -> HandBank:
        return cls(
            traj=entry["traj"].numpy().astype(np.float32),
            label=entry["label"].numpy().astype(np.int64),
            writer=entry["writer"].numpy().astype(np.int64),
            writers=tuple(entry["writers"]),
        )

    def __len__(self) -> int:
        return len(self.label)
