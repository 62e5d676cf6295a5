"""Cross-modal coherence: do generated samples belong to the class they were generated from?

For an input subset S and a target modality t, each test sample's inputs x_S are encoded and
x_t is generated (the posterior mean with ``temperature=0``, or a latent drawn with its standard
deviation scaled by ``temperature``). A generated trajectory or image is *coherent* when an
independent classifier (:mod:`prg.evaluation.classifiers`, trained on the training split)
assigns it the test sample's class; a generated label when its most probable class is the
test sample's class (this is the label accuracy from S). When t is in S the cell measures
reconstruction, not cross-modal transfer; the robustness table shows those too.

Coherence is reported exact and *folded*: the folded rate also counts a generated sample whose
class is a shape twin of the true one (o/O/0, x/X, i/I/l ...,
:data:`~prg.evaluation.classifiers.SHAPE_TWINS`), letters that are the same shape once size and
position are normalised away, so neither a classifier nor a reader can tell them apart.

Each generated trajectory and image is also read by a second, independently built classifier
(:mod:`prg.evaluation.second_readers`, :func:`generated_readings`);
:mod:`prg.evaluation.agreement` compares the two readings.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import torch
from torch import nn

from prg.evaluation.classifiers import FOLD, predict
from prg.models.base import Inputs, MultimodalVAE
from prg.models.modalities import MODALITIES


def coherence_cells(model: MultimodalVAE) -> list[tuple[str, tuple[str, ...]]]:
    """Every (target, input subset) the family can generate: each accepted subset x each
    generated modality."""
    return [(t, s) for s in model.accepted_inputs for t in model.generated_modalities]


@torch.no_grad()
def generated_classes(
    model: MultimodalVAE,
    target: str,
    given: tuple[str, ...],
    data: Inputs,
    classifiers: Mapping[str, nn.Module],
    temperature: float = 0.0,
    batch_size: int = 512,
    seed: int = 0,
    impute_steps: int = 0,
    posteriors: Posteriors | None = None,
) -> torch.Tensor:
    """Class assigned to each generated ``target`` sample (shape (N,), long): a generated label's
    most probable class, the classifier's (``classifiers[target]``) for anything else.
    ``posteriors``: ``model``'s posteriors on ``data``, shared with other cells
    (:class:`Posteriors`); None computes them for this call alone."""
    readers = (
        [] if MODALITIES[target].kind == "class" else [_classifier_reader(classifiers[target])]
    )
    return generated_readings(
        model, target, given, data, readers, temperature, batch_size, seed, impute_steps, posteriors
    )[:, 0]


def _classifier_reader(classifier: nn.Module) -> Callable[[torch.Tensor], torch.Tensor]:
    return lambda x: predict(classifier, x)


@torch.no_grad()
def generated_readings(
    model: MultimodalVAE,
    target: str,
    given: tuple[str, ...],
    data: Inputs,
    readers: Sequence[Callable[[torch.Tensor], torch.Tensor]],
    temperature: float = 0.0,
    batch_size: int = 512,
    seed: int = 0,
    impute_steps: int = 0,
    posteriors: Posteriors | None = None,
) -> torch.Tensor:
    """The class each reader assigns to each generated ``target`` sample; every reader reads the
    same generated samples.

    Parameters
    ----------
    model, target, given, data, temperature, batch_size, seed, impute_steps, posteriors
        As :func:`generated_classes`.
    readers : sequence of callables
        Each maps a batch of generated ``target`` samples to class ids (N,). Ignored for a
        generated label, whose most probable class is its only reading.

    Returns
    -------
    torch.Tensor
        Class ids, shape (N, R) with R = ``len(readers)`` (1 for a label), long.
    """
    if MODALITIES[target].kind == "class":
        readers = [lambda generated: generated.argmax(-1)]
    elif not readers:
        raise ValueError(f"generated {target} needs at least one reader")
    out = torch.empty(samples(data), len(readers), dtype=torch.long)
    for rows, generated in _generated_batches(
        model, target, given, data, temperature, batch_size, seed, impute_steps, posteriors
    ):
        for column, read in enumerate(readers):
            out[rows, column] = read(generated)
    return out


@torch.no_grad()
def generated_samples(
    model: MultimodalVAE,
    target: str,
    given: tuple[str, ...],
    data: Inputs,
    temperature: float = 0.0,
    batch_size: int = 512,
    seed: int = 0,
    impute_steps: int = 0,
    posteriors: Posteriors | None = None,
) -> torch.Tensor:
    """One generated ``target`` sample per test sample (shape (N, ...)), drawn as
    :func:`generated_classes` draws them."""
    return torch.cat(
        [
            g
            for _, g in _generated_batches(
                model, target, given, data, temperature, batch_size, seed, impute_steps, posteriors
            )
        ]
    )


def samples(data: Inputs) -> int:
    """How many samples ``data`` (full-split tensors, one per modality) holds."""
    return len(next(iter(data.values())))


class Posteriors:
    """One model's generation posteriors
    (:meth:`~prg.models.base.MultimodalVAE.generation_posterior`) on one test set, computed
    once per (input subset, impute steps, batch) and shared by every cell decoded from them:
    the targets of a subset, its posterior-mean and sampled kinds, and the roughness rows.
    Imputing is what makes sharing pay: each imputed posterior is ``impute_steps`` rounds of
    decoding and encoding every missing modality (MUSE from a trajectory: 20 image decodings
    and encodings)."""

    def __init__(self, model: MultimodalVAE, data: Inputs) -> None:
        self.model, self.data = model, data
        self._kept: dict[tuple, Any] = {}

    def get(self, given: tuple[str, ...], impute_steps: int, rows: slice) -> Any:
        key = (given, impute_steps, rows.start, rows.stop)
        if key not in self._kept:
            inputs = {m: self.data[m][rows] for m in given}
            self._kept[key] = self.model.generation_posterior(inputs, impute_steps)
        return self._kept[key]


def _generated_batches(
    model, target, given, data, temperature, batch_size, seed, impute_steps, posteriors=None
):
    if posteriors is None:
        posteriors = Posteriors(model, data)
    elif posteriors.model is not model or posteriors.data is not data:
        raise ValueError("posteriors were computed for another model or another test set")
    torch.manual_seed(seed)  # sampling draws latents from the global generator
    n = samples(data)
    for start in range(0, n, batch_size):
        rows = slice(start, min(start + batch_size, n))
        posterior = posteriors.get(given, impute_steps, rows)
        inputs = {m: data[m][rows] for m in given}
        generated = model.decode_posterior(posterior, inputs, target, 1, temperature)[0]
        yield rows, generated


def folded_correct(predicted: torch.Tensor, labels: torch.Tensor) -> torch.Tensor:
    """Whether each prediction lies in its true class's shape-twin group
    (:data:`~prg.evaluation.classifiers.SHAPE_TWINS`: o/O/0, x/X ... count as right)."""
    fold = torch.from_numpy(FOLD)
    return fold[predicted] == fold[labels]


def per_class_rate(correct: torch.Tensor, labels: torch.Tensor, num_classes: int) -> torch.Tensor:
    """Mean of ``correct`` within each class (NaN for a class with no samples)."""
    counts = torch.bincount(labels, minlength=num_classes).float()
    hits = torch.bincount(labels, weights=correct.float(), minlength=num_classes)
    return torch.where(counts > 0, hits / counts.clamp(min=1), torch.nan)
