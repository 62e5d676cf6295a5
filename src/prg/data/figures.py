"""Figures written next to a prepared dataset: samples per class, augmentations, images."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from prg.alphabet import ALPHABET
from prg.files import atomic_path
from prg.plotting import pyplot


def _save(fig, path: Path) -> None:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=80, bbox_inches="tight", metadata={"Software": None})


def write_dataset_figures(
    folder: str | os.PathLike, train: dict[str, np.ndarray], n_points: int, seed: int
) -> list[Path]:
    """Draw the sample sheet, the image sheet and the augmentation overlay for a training split.

    Parameters
    ----------
    folder : path
        Created if missing.
    train : dict
        Training split arrays (``traj`` (N, 2n) or (N, n, 2), ``image``, ``label``,
        ``augmented``, ``parent``).
    n_points : int
        Points per trajectory.
    seed : int
        Chooses which samples are shown.

    Returns
    -------
    list of Path
        The PNG files written.
    """
    plt = pyplot()
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    trajs = np.asarray(train["traj"]).reshape(len(train["label"]), n_points, 2)
    labels, augmented, parent = train["label"], train["augmented"], train["parent"]
    rng = np.random.default_rng(seed)
    written = []

    per_row = 8
    chosen = np.full((len(ALPHABET), per_row), -1)
    chosen_img = np.full((len(ALPHABET), per_row), -1)
    for c in range(len(ALPHABET)):
        originals = np.flatnonzero((labels == c) & ~augmented)
        pick = rng.choice(originals, size=min(per_row, len(originals)), replace=False)
        chosen[c, : len(pick)] = pick
        everything = np.flatnonzero(labels == c)
        pick = rng.choice(everything, size=min(per_row, len(everything)), replace=False)
        chosen_img[c, : len(pick)] = pick

    from matplotlib.collections import LineCollection

    fig, ax = plt.subplots(figsize=(2 * (per_row + 1) * 0.5, len(ALPHABET) / 2 * 0.5))
    lines, starts = [], []
    for c in range(len(ALPHABET)):
        row, col = divmod(c, 2)  # two classes per row, per_row samples each
        for k, idx in enumerate(chosen[c]):
            if idx >= 0:
                offset = np.array([2.4 * (col * (per_row + 1) + k), -2.4 * row])
                lines.append(trajs[idx] + offset)
                starts.append(lines[-1][0])
        ax.text(
            2.4 * (col * (per_row + 1)) - 1.8,
            -2.4 * row,
            ALPHABET[c],
            fontsize=9,
            va="center",
            ha="right",
        )
    ax.add_collection(LineCollection(lines, colors="black", linewidths=0.7))
    if starts:
        ax.plot(*np.array(starts).T, "o", ms=1.5, color="tab:red")
    ax.autoscale()
    ax.set_aspect("equal")
    ax.set_axis_off()
    ax.set_title("Training originals per class (red dot: pen down)", fontsize=9)
    written.append(folder / "samples_per_class.png")
    _save(fig, written[-1])
    plt.close(fig)

    size = train["image"].shape[-1]
    mosaic = np.zeros((len(ALPHABET) // 2 * (size + 2), 2 * per_row * (size + 2) + size))
    for c in range(len(ALPHABET)):
        row, col = divmod(c, 2)
        for k, idx in enumerate(chosen_img[c]):
            if idx >= 0:
                y, x = row * (size + 2), (col * (per_row + 1) + k) * (size + 2)
                mosaic[y : y + size, x : x + size] = train["image"][idx]
    fig, ax = plt.subplots(figsize=(mosaic.shape[1] / 40, mosaic.shape[0] / 40))
    ax.imshow(mosaic, cmap="gray_r", vmin=0, vmax=255, interpolation="nearest")
    ax.set_axis_off()
    ax.set_title(f"Rendered {size}x{size} images, 8 per class (0-9, A-Z, a-z)", fontsize=9)
    written.append(folder / "images_per_class.png")
    _save(fig, written[-1])
    plt.close(fig)

    parents = np.unique(parent[augmented]) if augmented.any() else np.array([], dtype=int)
    if len(parents):
        shown = rng.choice(parents, size=min(24, len(parents)), replace=False)
        cols = 6
        fig, axes = plt.subplots(
            -(-len(shown) // cols),
            cols,
            figsize=(cols * 1.6, -(-len(shown) // cols) * 1.6),
            squeeze=False,
        )
        for ax in axes.flat:
            ax.set_axis_off()
        for ax, p in zip(axes.flat, shown):
            children = np.flatnonzero(augmented & (parent == p))[:6]
            for child in children:
                ax.plot(trajs[child, :, 0], trajs[child, :, 1], lw=0.7, alpha=0.7)
            ax.plot(trajs[p, :, 0], trajs[p, :, 1], lw=1.6, color="black")
            ax.set_title(f"'{ALPHABET[labels[p]]}'", fontsize=8)
            ax.set_aspect("equal")
        fig.suptitle("Originals (black) overlaid with sigma-lognormal augmentations", fontsize=9)
        fig.tight_layout()
        written.append(folder / "augmentation.png")
        _save(fig, written[-1])
        plt.close(fig)
    return written
