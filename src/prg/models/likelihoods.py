"""Per-modality likelihoods p(x | decoder output). Every log-density sums over the sample's
dimensions and includes its normalising constant, so it is a true log-density (nats).

Each modality's likelihood family is the registry's (:data:`prg.models.modalities.MODALITIES`,
``likelihood``):

- ``gaussian`` (``traj``): a fixed standard deviation ``traj_std`` on every coordinate (the
  trajectory decoder outputs the mean). ``-log p = ||x - mu||^2 / (2 std^2) + 200 log(std sqrt(2 pi))``
  — squared error up to scale and a constant.
- ``categorical`` (``label``): over the 62 classes (decoder outputs logits); ``-log p`` is the
  cross-entropy.
- ``bernoulli`` (``image``): per pixel on **grey** targets in [0, 1] (decoder outputs logits);
  ``log p = sum x log sigmoid(l) + (1 - x) log(1 - sigmoid(l))`` — the binary cross-entropy the
  reference code trains with. For grey targets this is not a normalised density over [0, 1]
  images (it is one over binary images); Table I's image numbers follow this convention.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch
import torch.nn.functional as F

from prg.models.modalities import MODALITIES, NAMES, Modality


def gaussian_log_prob(
    mean: torch.Tensor, x: torch.Tensor, std: float, sample_dims: int = 1
) -> torch.Tensor:
    """log N(x; mean, std^2 I), summed over the last ``sample_dims`` dimensions."""
    n = math.prod(mean.shape[-sample_dims:])
    const = n * math.log(std * math.sqrt(2 * math.pi))
    return -((x - mean) ** 2).flatten(-sample_dims).sum(-1) / (2 * std**2) - const


def categorical_log_prob(logits: torch.Tensor, x: torch.Tensor) -> torch.Tensor:
    """log softmax(logits)[x]; ``x`` holds class indices."""
    logp = F.log_softmax(logits, dim=-1)
    index = x.expand(logp.shape[:-1]).unsqueeze(-1)
    return logp.gather(-1, index).squeeze(-1)


def bernoulli_log_prob(logits: torch.Tensor, x: torch.Tensor, sample_dims: int) -> torch.Tensor:
    """sum x log sigmoid(l) + (1 - x) log(1 - sigmoid(l)) over the last ``sample_dims``
    dimensions (minus the binary cross-entropy; ``x`` may be grey, in [0, 1])."""
    bce = F.binary_cross_entropy_with_logits(logits, x.expand_as(logits), reduction="none")
    return -bce.flatten(-sample_dims).sum(-1)


def _modality(name: str) -> Modality:
    if name not in MODALITIES:
        raise ValueError(f"unknown modality {name!r}: accepted {NAMES}")
    return MODALITIES[name]


@dataclass(frozen=True)
class Likelihoods:
    """The likelihood of each modality; ``traj_std`` is the std of the Gaussian likelihood (the
    trajectory's, the one Gaussian modality)."""

    traj_std: float = 0.1

    def __post_init__(self):
        if not self.traj_std > 0:
            raise ValueError(f"traj_std must be > 0, got {self.traj_std}")

    def log_prob(self, modality: str, params: torch.Tensor, x: torch.Tensor) -> torch.Tensor:
        """log p(x | params) per sample.

        Parameters
        ----------
        modality : a name of :data:`prg.models.modalities.MODALITIES` ("traj", "label", "image")
        params : Tensor
            Decoder output, shape (..., 200), (..., 62) or (..., 1, 28, 28).
        x : Tensor
            Data broadcastable against ``params``: (..., 200) float, (...,) long, (..., 1, 28, 28).

        Returns
        -------
        Tensor, shape (...)
        """
        spec = _modality(modality)
        if spec.likelihood == "gaussian":
            return gaussian_log_prob(params, x, self.traj_std, len(spec.shape))
        if spec.likelihood == "categorical":
            return categorical_log_prob(params, x)
        return bernoulli_log_prob(params, x, len(spec.shape))

    @staticmethod
    def mean(modality: str, params: torch.Tensor) -> torch.Tensor:
        """The distribution's mean in data space: trajectory, class probabilities, pixel
        probabilities."""
        kind = _modality(modality).likelihood
        if kind == "gaussian":
            return params
        if kind == "categorical":
            return params.softmax(-1)
        return params.sigmoid()

    @staticmethod
    def as_input(modality: str, params: torch.Tensor) -> torch.Tensor:
        """A decoded value in the form the modality's encoder takes: the :meth:`mean`, and for a
        categorical the most probable class."""
        mean = Likelihoods.mean(modality, params)
        return mean.argmax(-1) if _modality(modality).likelihood == "categorical" else mean
