"""Shared fixtures: a small synthetic data config and a prepared dataset built once per session."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent


def small_data_cfg(**overrides) -> dict:
    """The composed ``data`` node of conf/data/synthetic.yaml, shrunk for tests."""
    from prg.cli import compose_config

    cfg = compose_config(
        "prepare",
        [
            "data.synthetic.n_writers=5",
            "data.augment.per_class=3",
            *[f"{k}={v}" for k, v in overrides.items()],
        ],
    )
    from omegaconf import OmegaConf

    return OmegaConf.to_container(cfg.data, resolve=True)


@pytest.fixture(scope="session")
def small_dataset(tmp_path_factory) -> Path:
    """A prepared synthetic dataset (5 writers, 3 augmented samples per class); returns data_dir."""
    from prg.data.build import build_dataset

    data_dir = tmp_path_factory.mktemp("data")
    build_dataset(small_data_cfg(), data_dir, workers=1, progress=False, figures=False)
    return data_dir


def run_cli(*args: str, cwd: Path | None = None, env: dict | None = None, timeout: int = 300):
    """Run a console script of this environment; returns the CompletedProcess."""
    command = [str(BIN / args[0]), *args[1:]]
    full_env = {**os.environ, "PYTHONUNBUFFERED": "1", **(env or {})}
    return subprocess.run(
        command, cwd=cwd, env=full_env, capture_output=True, text=True, timeout=timeout
    )


def letter_like(rng: np.random.Generator, n: int = 60) -> np.ndarray:
    """A random smooth open curve (y down, arbitrary scale) standing in for a raw stroke."""
    t = np.linspace(0, 1, n)
    freqs = rng.uniform(0.3, 2.0, size=(2, 3))
    phases = rng.uniform(0, 2 * np.pi, size=(2, 3))
    amps = rng.uniform(0.5, 3.0, size=(2, 3))
    pts = (
        amps[:, None, :]
        * np.sin(2 * np.pi * freqs[:, None, :] * t[None, :, None] + phases[:, None, :])
    ).sum(-1)
    return pts.T * rng.uniform(10, 500)
