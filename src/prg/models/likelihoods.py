"""Per-modality likelihoods p(x | decoder output). Every log-density sums over the sample's
dimensions and includes its normalising constant, so it is a true log-density (nats).

- ``traj``: Gaussian with a fixed standard deviation ``traj_std`` on every coordinate (the
  trajectory decoder outputs the mean). ``-log p = ||x - mu||^2 / (2 std^2) + 200 log(std sqrt(2 pi))``
  — squared error up to scale and a constant.
- ``label``: categorical over the 62 classes (decoder outputs logits); ``-log p`` is the
  cross-entropy.
- ``image``: Bernoulli per pixel on **grey** targets in [0, 1] (decoder outputs logits);
  ``log p = sum x log sigmoid(l) + (1 - x) log(1 - sigmoid(l))`` — the binary cross-entropy the
  reference code trains with. For grey targets this is not a normalised density over [0, 1]
  images (it is one over binary images); Table I's image numbers follow this convention.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch
import torch.nn.functional as F

MODALITIES = ("traj", "label", "image")


@dataclass(frozen=True)
class Likelihoods:
    """The likelihood of each modality; ``traj_std`` is the trajectory Gaussian's std."""

    traj_std: float = 0.1

    def __post_init__(self):
        if not self.traj_std > 0:
            raise ValueError(f"traj_std must be > 0, got {self.traj_std}")

    def log_prob(self, modality: str, params: torch.Tensor, x: torch.Tensor) -> torch.Tensor:
        """log p(x | params) per sample.

        Parameters
        ----------
        modality : {"traj", "label", "image"}
        params : Tensor
            Decoder output, shape (..., 200), (..., 62) or (..., 1, 28, 28).
        x : Tensor
            Data broadcastable against ``params``: (..., 200) float, (...,) long, (..., 1, 28, 28).

        Returns
        -------
        Tensor, shape (...)
        """
        if modality == "traj":
            const = params.shape[-1] * math.log(self.traj_std * math.sqrt(2 * math.pi))
            return -((x - params) ** 2).sum(-1) / (2 * self.traj_std**2) - const
        if modality == "label":
            logp = F.log_softmax(params, dim=-1)
            index = x.expand(logp.shape[:-1]).unsqueeze(-1)
            return logp.gather(-1, index).squeeze(-1)
        if modality == "image":
            bce = F.binary_cross_entropy_with_logits(params, x.expand_as(params), reduction="none")
            return -bce.flatten(-3).sum(-1)
        raise ValueError(f"unknown modality {modality!r}: accepted {MODALITIES}")

    @staticmethod
    def mean(modality: str, params: torch.Tensor) -> torch.Tensor:
        """The distribution's mean in data space: trajectory, class probabilities, pixel
        probabilities."""
        if modality == "traj":
            return params
        if modality == "label":
            return params.softmax(-1)
        if modality == "image":
            return params.sigmoid()
        raise ValueError(f"unknown modality {modality!r}: accepted {MODALITIES}")
