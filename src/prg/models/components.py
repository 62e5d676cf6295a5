"""Modality encoders and decoders, exactly as the paper's appendix tables.

Every encoder maps its modality to the mean and log-variance of a diagonal Gaussian over a
``latent_dim``-dimensional code (16 in the paper); every decoder maps a code back to the
parameters of the modality's likelihood (:mod:`prg.models.likelihoods`): the trajectory mean
(200 values), label logits (62), image logits (1 x 28 x 28). LeakyReLU throughout (slope 0.01,
PyTorch's default). The tables list a LeakyReLU after the image decoder's last transposed
convolution; it is left out here because that layer's outputs are the Bernoulli logits, which
must range over all reals. Which network serves which modality is the registry's
(:data:`prg.models.modalities.MODALITIES`: ``encoder``, ``decoder``).
"""

from __future__ import annotations

from itertools import pairwise

import torch
from torch import nn

from prg.alphabet import NUM_CLASSES

TRAJ_DIM = 200
IMAGE_SHAPE = (1, 28, 28)


def mlp(sizes: list[int], final_activation: bool = True) -> nn.Sequential:
    """Linear layers with LeakyReLU between them (and after the last if asked)."""
    layers: list[nn.Module] = []
    for i, (n_in, n_out) in enumerate(pairwise(sizes)):
        layers.append(nn.Linear(n_in, n_out))
        if final_activation or i < len(sizes) - 2:
            layers.append(nn.LeakyReLU())
    return nn.Sequential(*layers)


class GaussianHead(nn.Module):
    """Two parallel linear layers: mean and log-variance ("FC 16, FC 16")."""

    def __init__(self, n_in: int, latent_dim: int):
        super().__init__()
        self.mu = nn.Linear(n_in, latent_dim)
        self.logvar = nn.Linear(n_in, latent_dim)

    def forward(self, h: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.mu(h), self.logvar(h)


class TrajectoryEncoder(nn.Module):
    """x_T (B, 200 [+ extra]) -> FC 512 x3 -> (mu, logvar) (B, latent_dim)."""

    def __init__(self, latent_dim: int = 16, hidden: int = 512, extra_inputs: int = 0):
        super().__init__()
        self.body = mlp([TRAJ_DIM + extra_inputs, hidden, hidden, hidden])
        self.head = GaussianHead(hidden, latent_dim)

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.head(self.body(x))


class TrajectoryDecoder(nn.Module):
    """z (B, latent_dim [+ extra]) -> FC 512 x3 -> FC 200: the trajectory mean."""

    def __init__(self, latent_dim: int = 16, hidden: int = 512, extra_inputs: int = 0):
        super().__init__()
        self.net = mlp([latent_dim + extra_inputs, hidden, hidden, hidden, TRAJ_DIM], False)

    def forward(self, z: torch.Tensor) -> torch.Tensor:
        return self.net(z)

    def zero_output_layer(self) -> None:
        """Start the last layer (512 -> 200) at zero, weights and bias.

        With PyTorch's default initialisation every decoded letter carries a fixed random
        pattern, ``W_0 h``, that is white from one point to the next; gradient descent removes
        it only along the directions the hidden features span, so early models write jittery
        letters. From zero, the layer holds only accumulated gradients of the reconstruction
        residuals, which are as smooth as the letters are. The network is unchanged; only its
        starting point is (the hidden layers still start random, so it still learns).
        """
        last = self.net[-1]
        nn.init.zeros_(last.weight)
        nn.init.zeros_(last.bias)


class LabelEncoder(nn.Module):
    """y (B,) long -> Embedding(62, 256) -> FC 256 x2 -> (mu, logvar)."""

    def __init__(self, latent_dim: int = 16, hidden: int = 256, num_classes: int = NUM_CLASSES):
        super().__init__()
        self.embed = nn.Embedding(num_classes, hidden)
        self.body = mlp([hidden, hidden, hidden])
        self.head = GaussianHead(hidden, latent_dim)

    def forward(self, y: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.head(self.body(self.embed(y)))


class LabelDecoder(nn.Module):
    """z -> FC 256 x3 -> FC 62: class logits."""

    def __init__(self, latent_dim: int = 16, hidden: int = 256, num_classes: int = NUM_CLASSES):
        super().__init__()
        self.net = mlp([latent_dim, hidden, hidden, hidden, num_classes], False)

    def forward(self, z: torch.Tensor) -> torch.Tensor:
        return self.net(z)


class ImageEncoder(nn.Module):
    """x_I (B, 1, 28, 28) -> Conv 64, 128, 256 (4x4, stride 2, pad 1) -> FC 512 -> (mu, logvar).

    Spatial sizes 28 -> 14 -> 7 -> 3, so the flattened feature has 256 * 3 * 3 = 2304 values.
    """

    def __init__(self, latent_dim: int = 16, hidden: int = 512):
        super().__init__()
        self.conv = nn.Sequential(
            nn.Conv2d(1, 64, 4, stride=2, padding=1),
            nn.LeakyReLU(),
            nn.Conv2d(64, 128, 4, stride=2, padding=1),
            nn.LeakyReLU(),
            nn.Conv2d(128, 256, 4, stride=2, padding=1),
            nn.LeakyReLU(),
            nn.Flatten(),
        )
        self.fc = mlp([256 * 3 * 3, hidden])
        self.head = GaussianHead(hidden, latent_dim)

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.head(self.fc(self.conv(x)))


class ImageDecoder(nn.Module):
    """z -> FC 512 -> FC 2304 -> ConvT 128 (out_padding 1), 64, 1 -> logits (B, 1, 28, 28).

    Spatial sizes 3 -> 7 -> 14 -> 28.
    """

    def __init__(self, latent_dim: int = 16, hidden: int = 512):
        super().__init__()
        self.fc = mlp([latent_dim, hidden, 256 * 3 * 3])
        self.deconv = nn.Sequential(
            nn.ConvTranspose2d(256, 128, 4, stride=2, padding=1, output_padding=1),
            nn.LeakyReLU(),
            nn.ConvTranspose2d(128, 64, 4, stride=2, padding=1),
            nn.LeakyReLU(),
            nn.ConvTranspose2d(64, 1, 4, stride=2, padding=1),
        )

    def forward(self, z: torch.Tensor) -> torch.Tensor:
        return self.deconv(self.fc(z).view(-1, 256, 3, 3))


def nearest_same_class(queries: torch.Tensor, values: torch.Tensor, labels: torch.Tensor):
    """Per query i, the squared distance to the nearest row j of ``values`` (same batch) with
    ``labels[j] == labels[i]`` (the batch-only candidates of the mode-seeking terms)."""
    distance = (queries[:, None, :] - values[None, :, :]).pow(2).sum(-1)
    return distance.masked_fill(labels[:, None] != labels[None, :], float("inf")).amin(1)


class ClassRing(nn.Module):
    """The last ``size`` vectors seen per class (a ring per class), for a nearest-neighbour
    search among real samples of the same class across batches (the mode-seeking terms). The
    models store training batches only.

    Its buffers are not saved in checkpoints: a resumed run refills them within a few batches,
    and a checkpoint keeps the paper's parameters only."""

    def __init__(self, num_classes: int, size: int, dim: int):
        super().__init__()
        self.size = size
        self.register_buffer("values", torch.zeros(num_classes, size, dim), persistent=False)
        self.register_buffer(
            "filled", torch.zeros(num_classes, size, dtype=torch.bool), persistent=False
        )
        self.register_buffer(
            "next_slot", torch.zeros(num_classes, dtype=torch.long), persistent=False
        )

    @torch.no_grad()
    def store(self, values: torch.Tensor, labels: torch.Tensor) -> None:
        """Write each row of ``values`` into its class's ring, oldest slot first."""
        onehot = nn.functional.one_hot(labels, self.values.shape[0])
        rank = (onehot.cumsum(0) - 1).gather(1, labels[:, None]).squeeze(1)
        slot = (self.next_slot[labels] + rank) % self.size
        self.values[labels, slot] = values.detach().to(self.values.dtype)
        self.filled[labels, slot] = True
        self.next_slot += onehot.sum(0)

    def nearest_distance(self, queries: torch.Tensor, labels: torch.Tensor) -> torch.Tensor:
        """Per query, the squared distance to the nearest stored vector of its class (inf when
        its class has none yet)."""
        distance = (queries[:, None, :] - self.values[labels]).pow(2).sum(-1)
        return distance.masked_fill(~self.filled[labels], float("inf")).amin(1)


def shift_images(
    images: torch.Tensor, max_shift: int, generator: torch.Generator | None = None
) -> torch.Tensor:
    """Each image ``(n, c, h, w)`` moved by its own random whole-pixel offset in
    ``[-max_shift, max_shift]`` along each axis, the uncovered border filled with background
    (0); offsets from ``generator`` (default: torch's global one). Written here because
    torchvision's ``RandomAffine`` draws one offset per call, not per sample, and the project
    does not otherwise need torchvision."""
    if max_shift <= 0:
        return images
    n, channels, height, width = images.shape
    padded = nn.functional.pad(images, (max_shift,) * 4)
    offsets = torch.randint(0, 2 * max_shift + 1, (2, n, 1), generator=generator).to(images.device)
    rows = offsets[0] + torch.arange(height, device=images.device)  # (n, h)
    cols = offsets[1] + torch.arange(width, device=images.device)  # (n, w)
    index = torch.arange(n, device=images.device)[:, None, None, None]
    channel = torch.arange(channels, device=images.device)[None, :, None, None]
    return padded[index, channel, rows[:, None, :, None], cols[:, None, None, :]]
