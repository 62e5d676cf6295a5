"""Represent: the model reads and decodes per-letter inputs (the torch half of Generate).

:func:`decode_letters` runs the model's generation map psi'_T on per-letter inputs (any subset of
modalities the family accepts; extra modalities a family cannot use are dropped and reported);
:func:`infer_text` reads a word's letters from its non-text channels (S given I and/or T).
"""

from __future__ import annotations

import logging
import math

import numpy as np
import torch

from prg.alphabet import char_to_label, label_to_char, text_to_labels
from prg.errors import UsageError
from prg.models.base import MODALITIES, MultimodalVAE
from prg.models.modalities import IMAGE, LABEL, TRAJ

log = logging.getLogger(__name__)


def usable_inputs(model: MultimodalVAE, inputs: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    """The largest subset of ``inputs`` the family accepts; dropped modalities are logged.

    Raises
    ------
    UsageError
        If the family accepts none of the given modalities.
    """
    given = tuple(m for m in MODALITIES if m in inputs)
    candidates = [s for s in model.accepted_inputs if set(s) <= set(given)]
    if not candidates:
        accepted = " or ".join("{" + ", ".join(s) + "}" for s in model.accepted_inputs)
        raise UsageError(
            f"{model.family} cannot use the given inputs {{{', '.join(given)}}}: it accepts "
            f"{accepted}"
        )
    # prefer more modalities; among equals, the family's own order (label before image for AVAE)
    best = max(candidates, key=len)
    dropped = [m for m in given if m not in best]
    if dropped:
        log.warning("%s uses %s; ignoring %s", model.family, list(best), dropped)
    return {m: inputs[m] for m in best}


@torch.no_grad()
def decode_letters(
    model: MultimodalVAE,
    inputs: dict[str, torch.Tensor],
    temperature: float = 0.0,
    seed: int = 0,
    impute_steps: int = 0,
) -> np.ndarray:
    """One generated trajectory per letter.

    Parameters
    ----------
    model : MultimodalVAE
    inputs : dict
        Per-letter model inputs, each with N rows (``label`` (N,), ``traj`` (N, 200), ``image``
        (N, 1, 28, 28)).
    temperature, seed, impute_steps : see :class:`GenerateSettings`.

    Returns
    -------
    ndarray, shape (N, 100, 2)
        Normalised letter trajectories (y up), as the training data.
    """
    chosen = usable_inputs(model, inputs)
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(seed)
        out = model.generate(chosen, TRAJ, n=1, temperature=temperature, impute_steps=impute_steps)[
            0
        ]
    return out.numpy().reshape(len(out), -1, 2).astype(np.float64)


def infer_text(model: MultimodalVAE, inputs: dict[str, torch.Tensor]) -> str:
    """The letters the model reads from the inputs (S given the inputs), for a word given without
    its text (e.g. images only): the layout needs each letter's class.

    Read from the posterior mean of the given channels, without imputation: imputing sharpens
    each letter's probabilities to 0 or 1 and throws away the second readings that the word's
    context (:func:`read_in_context`) chooses among. On ten demo words from the test split's
    letter images this reads 5 right, against 2 with imputation and the letters' first readings.
    """
    if LABEL not in model.generated_modalities:
        raise UsageError(
            f"{model.family} cannot read letters from its inputs: give the text too (text=...)"
        )
    chosen = usable_inputs(model, inputs)
    with torch.no_grad():
        probs = model.generate(chosen, LABEL)[0]
    return read_in_context(probs)


# Letters whose shape, once normalised for size and position, does not tell their kind: the
# capital and small forms of C O P S V W X Z, and a capital I and a small l (a vertical stroke).
SHAPE_TWINS = {**{c: c.swapcase() for c in "CcOoPpSsVvWwXxZz"}, "I": "l", "l": "I"}

# The label ranges of each kind of character (prg.alphabet: 0-9, A-Z, a-z).
_KIND_LABELS = (range(0, 10), range(10, 36), range(36, 62))


def read_in_context(probs: torch.Tensor) -> str:
    """The word a reader sees in per-letter class probabilities ``(n, 62)``.

    A word is written in one kind of character — small letters, capitals or digits — so each
    letter is read as its most probable character of the kind that makes the whole word most
    probable (the sum over letters of the log of each letter's best probability in that kind),
    as a reader reads a letter in its word: "DeII" becomes "bell" when b and l are those
    letters' most probable small letters, "ca5" becomes "cat", "jumP" becomes "jump". A letter
    counts the probability of its shape twin too (``SHAPE_TWINS``: P for p, I for l), since the
    shape cannot tell them apart. When two kinds are equally probable (a tie) each letter keeps
    its most probable character.
    """
    merged = probs.clone()
    for char, twin in SHAPE_TWINS.items():
        merged[:, char_to_label(char)] = (
            probs[:, char_to_label(char)] + probs[:, char_to_label(twin)]
        )
    logp = merged.clamp_min(1e-12).log()
    scores = [float(logp[:, kind.start : kind.stop].max(-1).values.sum()) for kind in _KIND_LABELS]
    ranked = sorted(scores, reverse=True)
    if math.isclose(ranked[0], ranked[1], rel_tol=1e-9, abs_tol=1e-9):
        labels = probs.argmax(-1)
    else:
        kind = _KIND_LABELS[scores.index(ranked[0])]
        labels = merged[:, kind.start : kind.stop].argmax(-1) + kind.start
    return "".join(label_to_char(int(i)) for i in labels)


def check_inputs(text: str, inputs: dict[str, torch.Tensor]) -> None:
    """One clear error for unsupported characters, no inputs, or a channel whose letter count
    differs from the text's."""
    letters = [c for c in text if c != " "]
    text_to_labels("".join(letters))
    if not inputs:
        raise UsageError("no inputs: give the word through at least one channel")
    options = {IMAGE: "images", TRAJ: "trajectories", LABEL: "text"}  # the user's names
    for modality, value in inputs.items():
        if len(value) != len(letters):
            raise UsageError(
                f"{options.get(modality, modality)}= gives {len(value)} letters but the text "
                f"{text!r} has {len(letters)} letters"
            )


def label_inputs(text: str) -> dict[str, torch.Tensor]:
    """The S channel of ``text``: one class id per non-space character."""
    letters = "".join(c for c in text if c != " ")
    return {LABEL: torch.as_tensor(text_to_labels(letters), dtype=torch.long)}
