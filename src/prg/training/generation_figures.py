"""Figures of what a model generates: reconstructions and cross-modal generations."""

from __future__ import annotations

import numpy as np
import torch

from prg.data.alphabet import ALPHABET, NUM_CLASSES
from prg.models.base import MultimodalVAE
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
    ax.imshow(image.reshape(28, 28), cmap="gray_r", vmin=0, vmax=1)


def trajectory_grid(trajs: np.ndarray, titles: list[str], cols: int = 16, title: str = ""):
    """Trajectories (N, 200) interleaved x, y -> a grid of small line plots."""
    return _grid(trajs, titles, cols, title, (0.7, 0.8), _draw_trajectory)


def image_grid(images: np.ndarray, titles: list[str], cols: int = 16, title: str = ""):
    """Images (N, 1, 28, 28) in [0, 1] -> a grid."""
    return _grid(images, titles, cols, title, (0.6, 0.7), _draw_image)


@torch.no_grad()
def generation_figures(model: MultimodalVAE, batch: dict[str, torch.Tensor]) -> dict:
    """Figures for a family: ``recon_<modality>``, ``label_to_traj`` (62 classes),
    ``image_to_traj``, ``traj_to_image`` — each only where the family supports it."""
    figures = {}
    n = len(next(iter(batch.values())))
    names = (
        [ALPHABET[int(y)] for y in batch["label"]] if "label" in batch else list(map(str, range(n)))
    )
    for m in model.generated_modalities:
        given = {m: batch[m]} if model.accepts({m: batch[m]}) else dict(batch)
        out = model.generate(given, m)[0].cpu().numpy()
        if m == "traj":
            both = np.concatenate([batch["traj"].cpu().numpy(), out])
            figures["recon_traj"] = trajectory_grid(
                both, names * 2, cols=n, title="trajectories: data (top), reconstruction"
            )
        elif m == "image":
            both = np.concatenate([batch["image"].cpu().numpy(), out])
            figures["recon_image"] = image_grid(
                both, names * 2, cols=n, title="images: data (top), reconstruction"
            )
        elif m == "label" and "traj" in batch:
            predicted = [ALPHABET[i] for i in out.argmax(-1)]
            figures["recon_label"] = trajectory_grid(
                batch["traj"].cpu().numpy(),
                [f"{a}->{b}" for a, b in zip(names, predicted)],
                cols=n,
                title="labels: data -> reconstruction",
            )
    device = next(model.parameters()).device
    if (
        "label" in batch
        and model.accepts({"label": batch["label"]})
        and "traj" in model.generated_modalities
    ):
        every = {"label": torch.arange(NUM_CLASSES, device=device)}
        out = model.generate(every, "traj")[0].cpu().numpy()
        figures["label_to_traj"] = trajectory_grid(
            out, list(ALPHABET), title="label -> trajectory (posterior mean), all 62 classes"
        )
    if (
        {"image", "traj"} <= set(batch)
        and model.accepts({"image": batch["image"]})
        and model.accepts({"traj": batch["traj"]})
    ):
        out = model.generate({"image": batch["image"]}, "traj")[0].cpu().numpy()
        figures["image_to_traj"] = trajectory_grid(out, names, cols=n, title="image -> trajectory")
        out = model.generate({"traj": batch["traj"]}, "image")[0].cpu().numpy()
        figures["traj_to_image"] = image_grid(out, names, cols=n, title="trajectory -> image")
    return figures
