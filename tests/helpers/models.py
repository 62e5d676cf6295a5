"""Helpers shared by the tests that were split out of tests/test_models.py."""

from __future__ import annotations

import torch
from torch import nn

from prg.models.avae import AVAE
from prg.models.cvae import CVAE
from prg.models.muse import MUSE

ALL = ("traj", "label", "image")


FAMILIES = {
    "cvae": ({"_target_": "prg.models.cvae.CVAE"}, ("traj", "label")),
    "avae_ts": (
        {"_target_": "prg.models.avae.AVAE", "modalities": ["traj", "label"]},
        ("traj", "label"),
    ),
    "avae_ti": (
        {"_target_": "prg.models.avae.AVAE", "modalities": ["traj", "image"]},
        ("traj", "image"),
    ),
    "muse": ({"_target_": "prg.models.muse.MUSE"}, ALL),
}


def make_model(family: str, seed: int = 0, **kwargs):
    torch.manual_seed(seed)
    if family == "cvae":
        return CVAE(**kwargs)
    if family == "avae_ts":
        return AVAE(("traj", "label"), **kwargs)
    if family == "avae_ti":
        return AVAE(("traj", "image"), **kwargs)
    return MUSE(**kwargs)


def make_batch(n: int = 8, seed: int = 0, modalities=ALL) -> dict[str, torch.Tensor]:
    """Seeded fake data in the datamodule's format (trajectories of O(0.3), grey images)."""
    g = torch.Generator().manual_seed(seed)
    batch = {
        "traj": torch.randn(n, 200, generator=g) * 0.3,
        "label": torch.randint(0, 62, (n,), generator=g),
        "image": torch.rand(n, 1, 28, 28, generator=g),
    }
    return {m: batch[m] for m in modalities}


def linear_sizes(module: nn.Module) -> list[tuple[int, int]]:
    return [(m.in_features, m.out_features) for m in module.modules() if isinstance(m, nn.Linear)]


# ---- elbo ----------------------------------------------------------------------------------
TERMS = {
    "cvae": {"rec_traj", "kl", "elbo", "loss"},
    "avae_ts": {"rec_traj", "kl_traj", "rec_label", "kl_label", "skl", "loss"},
    "avae_ti": {"rec_traj", "kl_traj", "rec_image", "kl_image", "skl", "loss"},
    "muse": {f"{k}_{m}" for k in ("rec", "kl", "top_rec") for m in ALL}
    | {"top_kl", "subset_skl", "loss"},
}
