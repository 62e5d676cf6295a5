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
    from prg.commands.cli import compose_config

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
def untrained_muse_checkpoint(tmp_path_factory) -> Path:
    """An untrained MUSE saved the way training saves it (plumbing, not handwriting quality)."""
    import torch
    from omegaconf import OmegaConf

    from prg.commands.cli import compose_config
    from prg.models.module import PRGModule

    node = OmegaConf.to_container(
        compose_config("train", ["model=muse"]).model.module, resolve=True
    )
    torch.manual_seed(0)
    module = PRGModule(model=node["model"], optimizer=node["optimizer"])
    path = tmp_path_factory.mktemp("ckpt") / "muse.ckpt"
    ckpt = {"state_dict": module.state_dict(), "hyper_parameters": dict(module.hparams)}
    ckpt["hands"] = stand_in_hands().to_checkpoint()  # as training keeps its writers' letters
    torch.save(ckpt, path)
    return path


def stand_in_hands(n_writers: int = 3, seed: int = 0):
    """A :class:`~prg.data.hands.HandBank` of random letter-like strokes: every class written
    once by each of ``n_writers`` writers (plumbing, not handwriting)."""
    from prg.alphabet import NUM_CLASSES
    from prg.data.hands import HandBank
    from prg.pipeline.perceive import perceive_trajectories

    rng = np.random.default_rng(seed)
    n = n_writers * NUM_CLASSES
    traj = perceive_trajectories([letter_like(rng) for _ in range(n)], y_down=True)
    return HandBank(
        traj=traj,
        label=np.tile(np.arange(NUM_CLASSES), n_writers),
        writer=np.repeat(np.arange(n_writers), NUM_CLASSES),
        writers=tuple(f"w{i}" for i in range(n_writers)),
    )


@pytest.fixture(scope="session")
def small_dataset(tmp_path_factory) -> Path:
    """A prepared synthetic dataset (5 writers, 3 augmented samples per class); returns data_dir."""
    from prg.data.build import build_dataset

    data_dir = tmp_path_factory.mktemp("data")
    build_dataset(small_data_cfg(), data_dir, workers=1, progress=False, figures=False)
    return data_dir


def run_cli(*args: str, cwd: Path | None = None, env: dict | None = None, timeout: int = 300):
    """Run a console script of this environment; returns the CompletedProcess. Run in ``cwd``,
    the command's project root is ``cwd`` unless ``env`` sets ``PRG_ROOT`` (a test's command
    never writes logs or runs into the checkout's own folders)."""
    command = [str(BIN / args[0]), *args[1:]]
    root = {"PRG_ROOT": str(cwd)} if cwd is not None else {}
    full_env = {**os.environ, "PYTHONUNBUFFERED": "1", **root, **(env or {})}
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


def writer_variation(pts: np.ndarray, u: np.ndarray, rng: np.random.Generator, amount: float):
    """A writer-like variation of a curve sampled at ``u``: a random affine map plus a
    low-frequency wobble; returns 100 normalised equidistant points."""
    from prg.data.preprocess import normalise, resample_arclength

    if pts.shape[0] != u.shape[0]:
        pts = resample_arclength(pts, u.shape[0])
    pts = pts @ (np.eye(2) + rng.normal(0, amount, (2, 2))).T
    k = np.arange(1, 4)
    for d in range(2):
        wobble = rng.normal(0, amount / 2, 3) * np.sin(
            np.pi * k * u[:, None] + rng.uniform(0, 3, 3)
        )
        pts[:, d] += wobble.sum(axis=1)
    return normalise(resample_arclength(pts, 100))


def wait_for_pending_runs(root: Path, timeout: float = 120) -> None:
    """Wait until the MLflow runs that commands under project ``root`` handed to background
    loggers (``prg.tracking.task_run(background=True)``) are in the store: their files under
    ``logs/pending-runs/`` are gone. Fails with the loggers' log if one is still there."""
    import time

    folder = root / "logs" / "pending-runs"
    deadline = time.monotonic() + timeout
    while any(folder.glob("*.json")):
        if time.monotonic() > deadline:
            log = folder / "log.txt"
            pytest.fail(
                f"pending runs not logged: {log.read_text()[-2000:] if log.exists() else ''}"
            )
        time.sleep(0.1)
