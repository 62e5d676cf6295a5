"""Figures of what a model generates: reconstructions and cross-modal generations."""

from __future__ import annotations

import numpy as np
import torch

from prg.alphabet import ALPHABET, NUM_CLASSES
from prg.models.base import MultimodalVAE
from prg.models.modalities import IMAGE, LABEL, MODALITIES, TRAJ
from prg.plotting import pyplot


def _grid(items, titles: list[str], cols: int, title: str, cell: tuple[float, float], draw):
    """One small axes per item, ``draw(ax, item)`` in each, titles above."""
    plt = pyplot()
    rows = -(-len(items) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(cols * cell[0], rows * cell[1]), squeeze=False)
    for ax in axes.flat:
        ax.set_axis_off()
    for ax, item, name in zip(axes.flat, items, titles):
        draw(ax, np.asarray(item))
        ax.set_title(name, fontsize=7)
    fig.suptitle(title, fontsize=9)
    return fig


def _draw_trajectory(ax, traj: np.ndarray) -> None:
    pts = traj.reshape(-1, 2)
    ax.plot(pts[:, 0], pts[:, 1], lw=0.9, color="black")
    ax.plot(pts[0, 0], pts[0, 1], "o", ms=1.5, color="tab:red")
    ax.set_aspect("equal")


def _draw_image(ax, image: np.ndarray) -> None:
    ax.imshow(image.reshape(image.shape[-2:]), cmap="gray_r", vmin=0, vmax=1)


def trajectory_grid(trajs: np.ndarray, titles: list[str], cols: int = 16, title: str = ""):
    """Trajectories (N, 200) interleaved x, y -> a grid of small line plots."""
    return _grid(trajs, titles, cols, title, (0.7, 0.8), _draw_trajectory)


def image_grid(images: np.ndarray, titles: list[str], cols: int = 16, title: str = ""):
    """Images (N, 1, 28, 28) in [0, 1] -> a grid."""
    return _grid(images, titles, cols, title, (0.6, 0.7), _draw_image)


def spread_examples(labels: np.ndarray, n: int, seed: int) -> np.ndarray:
    """Indices of ``n`` samples whose classes spread evenly over the classes in ``labels``, in
    class order (digits, uppercase, lowercase: with all 62, ``n=8`` gives 0 9 H Q Z i q z), one
    sample of each drawn with ``seed`` (more samples than classes: classes repeat)."""
    present = np.unique(labels)
    classes = present[np.round(np.linspace(0, len(present) - 1, n)).astype(int)]
    rng = np.random.default_rng(seed)
    picked: list[int] = []
    for c in classes:
        of_class = np.flatnonzero(labels == c)
        unused = np.setdiff1d(of_class, picked)
        picked.append(int(rng.choice(unused if len(unused) else of_class)))
    return np.array(picked)


GRIDS = {"points": trajectory_grid, "pixels": image_grid}
"""The grid figure of each kind of modality (:data:`prg.models.modalities.KINDS`; class labels are shown
as the titles of others)."""


def grid_of(modality: str):
    """The function that draws samples of ``modality`` in a grid (:data:`GRIDS`), or None."""
    return GRIDS.get(MODALITIES[modality].kind)


@torch.no_grad()
def generation_figures(
    model: MultimodalVAE, batch: dict[str, torch.Tensor], names: list[str] | None = None
) -> dict:
    """Figures for a family: ``recon_<modality>``, ``label_to_traj`` (62 classes),
    ``image_to_traj``, ``traj_to_image`` — each only where the family supports it. ``names``
    titles the samples of ``batch`` (default: their classes where the batch has labels)."""
    figures = {}
    n = len(next(iter(batch.values())))
    if not names:
        names = (
            [ALPHABET[int(y)] for y in batch[LABEL]] if LABEL in batch else [*map(str, range(n))]
        )
    for m in model.generated_modalities:
        given = {m: batch[m]} if model.accepts({m: batch[m]}) else dict(batch)
        out = model.generate(given, m)[0].cpu().numpy()
        grid = grid_of(m)
        if grid is not None:
            both = np.concatenate([batch[m].cpu().numpy(), out])
            figures[f"recon_{m}"] = grid(
                both, names * 2, cols=n, title=f"{MODALITIES[m].plural}: data (top), reconstruction"
            )
        elif m == LABEL and TRAJ in batch:
            predicted = [ALPHABET[i] for i in out.argmax(-1)]
            figures["recon_label"] = trajectory_grid(
                batch[TRAJ].cpu().numpy(),
                [f"{a}->{b}" for a, b in zip(names, predicted)],
                cols=n,
                title="labels: data -> reconstruction",
            )
    # the paper's cross-modal generations: a letter of each class, images <-> trajectories
    device = next(model.parameters()).device
    if (
        LABEL in batch
        and model.accepts({LABEL: batch[LABEL]})
        and TRAJ in model.generated_modalities
    ):
        every = {LABEL: torch.arange(NUM_CLASSES, device=device)}
        out = model.generate(every, TRAJ)[0].cpu().numpy()
        figures["label_to_traj"] = trajectory_grid(
            out, list(ALPHABET), title="label -> trajectory (posterior mean), all 62 classes"
        )
    if (
        {IMAGE, TRAJ} <= set(batch)
        and model.accepts({IMAGE: batch[IMAGE]})
        and model.accepts({TRAJ: batch[TRAJ]})
    ):
        out = model.generate({IMAGE: batch[IMAGE]}, TRAJ)[0].cpu().numpy()
        figures["image_to_traj"] = trajectory_grid(out, names, cols=n, title="image -> trajectory")
        out = model.generate({TRAJ: batch[TRAJ]}, IMAGE)[0].cpu().numpy()
        figures["traj_to_image"] = image_grid(out, names, cols=n, title="trajectory -> image")
    return figures
