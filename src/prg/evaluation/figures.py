"""Figures of an evaluation: what each model generates across modalities, one test sample per
class, and its coherence per class."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np
import torch

from prg.alphabet import ALPHABET, NUM_CLASSES
from prg.evaluation.coherence import coherence_cells
from prg.models.base import MultimodalVAE
from prg.models.modalities import LABEL, LETTER
from prg.training.generation_figures import grid_of


def evaluation_figures(
    models: Mapping[str, MultimodalVAE],
    per_class: Mapping[tuple[str, str, str, str], np.ndarray],
    data: dict[str, torch.Tensor],
    folder: Path,
    readers: Mapping[str, Sequence[Callable[[torch.Tensor], torch.Tensor]]] | None = None,
) -> None:
    """Save into ``folder``, for each model: ``<name>_<T>_given_<S>.png``, the posterior mean
    of every cross-modal generation it supports that can be drawn (trajectories, images), from
    the first test sample of each class; ``<name>_coherence_per_class.png``, its coherence per
    class (``per_class``: (model, target, given subset, kind) -> rates, the ``mean`` kind).

    With ``readers`` (modality -> the first and second classifier as callables, batch -> class
    ids) each drawn sample's title also gives every classifier's reading of it, ``A: A/m``: the
    class it was generated from, then the first and the second classifier's verdicts."""
    from prg.plotting import pyplot

    plt = pyplot()
    first = [
        int(np.flatnonzero(data[LABEL].numpy() == c)[0])
        for c in range(NUM_CLASSES)
        if (data[LABEL] == c).any()
    ]
    index = torch.tensor(first)
    names = [ALPHABET[int(c)] for c in data[LABEL][index]]
    for name, model in models.items():
        for target, given in coherence_cells(model):
            draw = grid_of(target)
            if draw is None or target in given:
                continue
            out = model.generate({m: data[m][index] for m in given}, target)[0].numpy()
            label = f"{LETTER[target]}_given_{''.join(LETTER[m] for m in given)}"
            title = f"{name}: {label} (posterior mean), one test sample per class"
            titles = names
            if readers and target in readers:
                read = [r(torch.as_tensor(out)) for r in readers[target]]
                titles = [
                    f"{n}: {'/'.join(ALPHABET[int(v[i])] for v in read)}"
                    for i, n in enumerate(names)
                ]
                title += "; titles: class: first/second classifier's reading"
            fig = draw(out, titles, title=title)
            fig.savefig(folder / f"{name}_{label}.png", dpi=110)
            plt.close(fig)
        keys = [k for k in per_class if k[0] == name and k[3] == "mean"]
        if keys:
            matrix = np.stack([per_class[k] for k in keys])
            fig, ax = plt.subplots(figsize=(14, 0.35 * len(keys) + 1.2))
            ax.imshow(matrix, vmin=0, vmax=1, cmap="viridis", aspect="auto")
            ax.set_yticks(
                range(len(keys)), [f"{LETTER[k[1]]} | {{{k[2]}}}" for k in keys], fontsize=7
            )
            ax.set_xticks(range(NUM_CLASSES), list(ALPHABET), fontsize=6)
            ax.set_title(f"{name}: coherence per class (posterior mean generation)", fontsize=9)
            fig.colorbar(ax.images[0], ax=ax, fraction=0.02)
            fig.tight_layout()
            fig.savefig(folder / f"{name}_coherence_per_class.png", dpi=110)
            plt.close(fig)
