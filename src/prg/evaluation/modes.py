"""Generation modes side by side: how alike generated letters are to held-out writers' letters.

For each family and decoding mode, ``n_per_class`` letters of every class are generated from
their labels and compared, class by class, with the test split's letters (writers no model
saw), in the normalised 200-d trajectory space (:mod:`prg.evaluation.likeness`):

- ``legible``: share of generated letters the project's trajectory classifier reads as their
  class, shape twins folded (o/O/0 ...);
- ``precision`` / ``recall``: k-NN precision and recall (Kynkäänniemi et al. 2019, k = 3);
- ``c2st``: cross-validated accuracy of a linear classifier telling generated from real (0.5:
  indistinguishable);
- ``spread``: median within-class distance, generated over real (1: as varied as writers).

The reference rows are real letters scored the same way: ``n_per_class`` letters per class of
the validation split's writers (other held-out writers: what "as good as the data" means on
each measure), and of the training split's originals (what a model that reproduces its
training writers reaches).

Modes (:data:`MODES`): ``mean`` the paper's posterior mean of the label; ``imputed`` MUSE's
mean after imputing the missing modalities (the default before hands); ``sampled`` latents
drawn from the label's posterior at temperature 0.5 and 1; ``hand`` (the default): a real
writer's letter posterior sampled at ``hand_temperature`` (:mod:`prg.pipeline.hands`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
import torch
from torch import nn

from prg.alphabet import NUM_CLASSES
from prg.data.hands import HandBank
from prg.evaluation.classifiers import folded_accuracy, predict
from prg.evaluation.likeness import likeness
from prg.models.base import MultimodalVAE
from prg.models.modalities import LABEL, TRAJ
from prg.pipeline.hands import components, decode_in_hand, decoder_bias, random_hand


@dataclass(frozen=True)
class Mode:
    """A decoding mode: its name in the report, and how it draws letters from labels."""

    name: str
    kind: str  # "posterior" or "hand"
    temperature: float = 0.0
    impute_steps: int = 0


#: The measures of each row of the likeness table: ``legible`` read by the trajectory classifier
#: (an MLP on the points, which also reads their order), ``legible_shape`` by the second reader
#: (the letter drawn, then read by the image classifier: the shape alone), both folded.
LIKENESS_MEASURES = ("legible", "legible_shape", "precision", "recall", "c2st", "spread")

#: The modes every family is scored in (``imputed`` only where the family imputes).
MODES = (
    Mode("mean (paper)", "posterior"),
    Mode("imputed", "posterior", impute_steps=20),
    Mode("sampled T=0.5", "posterior", temperature=0.5),
    Mode("sampled T=1", "posterior", temperature=1.0),
    Mode("hand T=0", "hand", temperature=0.0),
    Mode("hand (default)", "hand", temperature=0.5),
    Mode("hand T=1", "hand", temperature=1.0),
)


def originals(arrays: Mapping[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A split's original letters: trajectories (N, 200), labels (N,), writers (N,)."""
    keep = ~np.asarray(arrays["augmented"], dtype=bool)
    return (
        np.asarray(arrays["traj"], dtype=np.float32)[keep],
        np.asarray(arrays["label"], dtype=np.int64)[keep],
        np.asarray(arrays["writer"]).astype(str)[keep],
    )


def by_class(traj: np.ndarray, labels: np.ndarray) -> dict[int, np.ndarray]:
    """class -> its rows of ``traj``."""
    return {int(c): traj[labels == c] for c in np.unique(labels)}


def subsample(traj: np.ndarray, labels: np.ndarray, n_per_class: int, seed: int) -> dict:
    """At most ``n_per_class`` rows of each class, drawn without replacement (seeded)."""
    rng = np.random.default_rng(seed)
    out = {}
    for c, rows in by_class(traj, labels).items():
        out[c] = rows[rng.permutation(len(rows))[:n_per_class]]
    return out


@torch.no_grad()
def generate_by_class(
    model: MultimodalVAE, mode: Mode, n_per_class: int, seed: int, bank: HandBank | None
) -> np.ndarray:
    """``n_per_class`` letters of every class, shape (n_per_class, NUM_CLASSES, 200).

    In the hand modes letter i of class c is written in the hand of seed
    ``seed + i * NUM_CLASSES + c``: the letters of a class come from different writers, and the
    classes do not share one draw of writers (ten hands for all 62 classes would make every
    class's measures hang on the same ten people)."""
    labels = np.arange(NUM_CLASSES)
    bias = decoder_bias(model, bank) if mode.kind == "hand" and bank is not None else None
    rounds = []
    for i in range(n_per_class):
        if mode.kind == "hand":
            if bank is None:
                raise ValueError(f"{model.family}: the hand modes need the checkpoint's hands")
            seeds = seed + i * NUM_CLASSES + labels
            chosen = np.concatenate(
                [
                    components(bank, random_hand(bank, int(s)), labels[c : c + 1], int(s))
                    for c, s in enumerate(seeds)
                ]
            )  # a random hand has no map: its letters are the writer's (write_in_hand's)
            letters = decode_in_hand(model, chosen, labels, mode.temperature, seed + i, bias)
            rounds.append(letters.reshape(NUM_CLASSES, -1))
        else:
            torch.manual_seed(seed + i)
            out = model.generate(
                {LABEL: torch.as_tensor(labels)},
                TRAJ,
                n=1,
                temperature=mode.temperature,
                impute_steps=mode.impute_steps,
            )[0]
            rounds.append(out.numpy().astype(np.float64))
    return np.stack(rounds)


def score(
    generated: Mapping[int, np.ndarray],
    real: Mapping[int, np.ndarray],
    classify: Callable[[np.ndarray], np.ndarray],
    seed: int,
    read_shape: Callable[[np.ndarray], np.ndarray] | None = None,
) -> dict[str, float]:
    """The measures of one row: ``legible`` (``classify``) and ``legible_shape`` (``read_shape``;
    NaN without it) over every generated letter, the rest per class against ``real`` and
    averaged (:func:`prg.evaluation.likeness.likeness`)."""
    labels = np.concatenate([np.full(len(v), c) for c, v in generated.items()])
    letters = np.concatenate([np.asarray(v, dtype=np.float32) for v in generated.values()])
    row = {
        "legible": folded_accuracy(classify(letters), labels),
        "legible_shape": (
            folded_accuracy(read_shape(letters), labels) if read_shape else float("nan")
        ),
    }
    row.update(likeness(real, generated, seed=seed))
    return row


def mode_rows(
    models: Mapping[str, tuple[MultimodalVAE, HandBank | None]],
    test: Mapping[str, np.ndarray],
    references: Mapping[str, Mapping[str, np.ndarray]],
    classifier: nn.Module,
    n_per_class: int = 10,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
    shape_reader: Callable[[torch.Tensor], torch.Tensor] | None = None,
) -> list[dict]:
    """The likeness table: one row per reference split, then per family x mode.

    Parameters
    ----------
    models : name -> (model, its checkpoint's hands)
    test : the test split's arrays (the real letters every row is compared with)
    references : row name -> a split's arrays (e.g. the validation split's)
    classifier : the project's trajectory classifier
    shape_reader : the second trajectory reader (batch -> class ids,
        :class:`prg.evaluation.second_readers.RenderedReader`), for ``legible_shape``
    """
    real = by_class(*originals(test)[:2])

    def classify(letters: np.ndarray) -> np.ndarray:
        return predict(classifier, torch.from_numpy(letters)).numpy()

    def read_shape(letters: np.ndarray) -> np.ndarray:
        return np.asarray(shape_reader(torch.from_numpy(letters)))

    def scored(generated, real):
        return score(generated, real, classify, seed, read_shape if shape_reader else None)

    rows = []
    for name, arrays in references.items():
        traj, labels, _ = originals(arrays)
        sample = subsample(traj, labels, n_per_class, seed)
        rows.append({"family": "real", "mode": name, **scored(sample, real)})
    for family, (model, bank) in models.items():
        for mode in MODES:
            if mode.impute_steps and not model.imputes_missing:
                continue
            if mode.kind == "hand" and bank is None:
                continue
            if mode.kind == "posterior" and (LABEL,) not in model.accepted_inputs:
                continue  # avae_ti: no label channel to decode from
            if progress:
                progress(f"{family} {mode.name}")
            letters = generate_by_class(model, mode, n_per_class, seed, bank)
            generated = {c: letters[:, c] for c in range(NUM_CLASSES)}
            rows.append({"family": family, "mode": mode.name, **scored(generated, real)})
    return rows
