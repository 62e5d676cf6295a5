"""Tiny fixed networks and hand formulas for the tests of the baseline families (MVAE, MMVAE,
MoPoE): experts that return set Gaussians, linear decoders with set weights, and the Gaussian,
categorical and KL formulas written out in numpy."""

from __future__ import annotations

import math

import numpy as np
import torch
from torch import nn

from prg.data.store import load_split
from prg.models.modalities import MODALITIES

STD = 0.1  # traj_std of every family


class FixedExpert(nn.Module):
    """An expert whose output is the set (mu, logvar), shape (B, d), whatever its input."""

    def __init__(self, mu, logvar):
        super().__init__()
        self.mu = nn.Parameter(torch.tensor(mu, dtype=torch.float32))
        self.logvar = nn.Parameter(torch.tensor(logvar, dtype=torch.float32))

    def forward(self, x):
        return self.mu, self.logvar


def linear_decoder(d: int, out: int, seed: int) -> nn.Linear:
    """A linear decoder z (d) -> out with seeded weights of O(1)."""
    layer = nn.Linear(d, out)
    g = torch.Generator().manual_seed(seed)
    with torch.no_grad():
        layer.weight.copy_(torch.randn(out, d, generator=g))
        layer.bias.copy_(torch.randn(out, generator=g) * 0.1)
    return layer


def weights_of(layer: nn.Linear) -> tuple[np.ndarray, np.ndarray]:
    return layer.weight.detach().double().numpy(), layer.bias.detach().double().numpy()


# ---- formulas (numpy, float64) -----------------------------------------------------------
def gauss_logpdf(z, mu, var):
    """log N(z; mu, diag var), summed over the last axis."""
    return (-0.5 * ((z - mu) ** 2 / var + np.log(2 * math.pi * var))).sum(-1)


def traj_logp(mean, x):
    """Gaussian likelihood of 200 coordinates with std :data:`STD`."""
    n = mean.shape[-1]
    return -((x - mean) ** 2).sum(-1) / (2 * STD**2) - n * math.log(STD * math.sqrt(2 * math.pi))


def label_logp(logits, y):
    """log softmax(logits)[y] (logits (..., B, C), y (B,))."""
    m = logits.max(-1, keepdims=True)
    logsm = logits - m - np.log(np.exp(logits - m).sum(-1, keepdims=True))
    index = np.broadcast_to(y[..., None], (*logsm.shape[:-1], 1))
    return np.take_along_axis(logsm, index, -1)[..., 0]


def kl_std_normal(mu, var):
    return 0.5 * (mu**2 + var - 1 - np.log(var)).sum(-1)


def poe(mus, variances, prior: bool):
    """Product of Gaussian experts: precision the sum of precisions (+1 for N(0, I))."""
    precision = sum(1 / v for v in variances) + (1.0 if prior else 0.0)
    mean = sum(m / v for m, v in zip(mus, variances, strict=True)) / precision
    return mean, 1 / precision


def logmeanexp(a, axis=0):
    m = a.max(axis, keepdims=True)
    return (m + np.log(np.exp(a - m).mean(axis, keepdims=True))).squeeze(axis)


# ---- the small dataset ---------------------------------------------------------------------
def small_batches(data_dir, n: int = 32, size: int = 16) -> list[dict[str, torch.Tensor]]:
    """The first ``n`` training samples of the small prepared dataset, as model batches."""
    arrays = load_split(data_dir / "prepared" / "synthetic" / "train.npz")
    data = {m: MODALITIES[m].to_tensor(arrays[m][:n]) for m in ("traj", "label", "image")}
    return [{m: x[i : i + size] for m, x in data.items()} for i in range(0, n, size)]


def loss_falls(model, batches, steps: int = 30, lr: float = 2e-3) -> tuple[float, float]:
    """Mean loss over the first and the last 5 of ``steps`` Adam steps cycling ``batches``.

    One torch thread: on a shared 2-core machine two threads ran these steps 20-35 times
    slower than one (measured: MoPoE 1.6 s against 0.086 s a step)."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        torch.manual_seed(0)
        opt = torch.optim.Adam(model.parameters(), lr=lr)
        losses = []
        for step in range(steps):
            loss = model.elbo(batches[step % len(batches)])["loss"]
            opt.zero_grad()
            loss.backward()
            opt.step()
            losses.append(loss.item())
    finally:
        torch.set_num_threads(threads)
    return float(np.mean(losses[:5])), float(np.mean(losses[-5:]))
