"""Agreement of the two classifiers that read each generated sample, and its report section.

Coherence reads every generated trajectory and image twice: by the first classifier of its
modality (:mod:`prg.evaluation.classifiers`) and by a second, independently built one
(:mod:`prg.evaluation.second_readers`). :func:`agreement` compares the two readings of a cell;
:func:`agreement_markdown` is coherence.md's section on them, :func:`mark` flags a folded rate
of the main table on which they disagree by more than :data:`DISAGREEMENT`.
"""

from __future__ import annotations

from collections.abc import Callable

import torch

from prg.evaluation.classifiers import FOLD
from prg.evaluation.coherence import folded_correct
from prg.models.modalities import LETTER

SECOND_KEYS = (
    "coherence_second",
    "coherence_folded_second",
    "agreement",
    "agreement_folded",
    "difference",
    "difference_folded",
    "coherence_folded_both",
)
"""Keys of a coherence row that compare the two classifiers (:func:`prg.evaluation.run.coherence_rows`)."""


METRIC_SECOND_KEYS = (
    "coherence_second",
    "coherence_folded_second",
    "agreement",
    "agreement_folded",
)
"""The comparisons of the two classifiers that go into metrics.json (the differences follow)."""


def second_metric_key(row: dict, key: str) -> str:
    """``coherence_second_T_given_S``, ``agreement_folded_sampled_T_given_S`` ..."""
    kind = "" if row["kind"] == "mean" else f"_{row['kind']}"
    return f"{key}{kind}_{LETTER[row['target']]}_given_{row['given'].replace(',', '')}"


def agreement(first: torch.Tensor, second: torch.Tensor, labels: torch.Tensor) -> dict[str, float]:
    """How two classifiers' readings of the same generated samples compare.

    Parameters
    ----------
    first, second : torch.Tensor
        Class ids (N,) assigned by the first and the second classifier.
    labels : torch.Tensor
        The classes the samples were generated from (N,).

    Returns
    -------
    dict
        ``coherence_second`` and ``coherence_folded_second``: the second classifier's exact and
        folded coherence; ``agreement``: the share of samples to which both assign the same
        class; ``agreement_folded``: ... the same shape-twin group; ``difference`` and
        ``difference_folded``: the first classifier's coherence minus the second's;
        ``coherence_folded_both``: the share that both read as the true class or its twin.
    """
    first_folded = folded_correct(first, labels).float()
    second_folded = folded_correct(second, labels).float()
    fold = torch.from_numpy(FOLD)
    first_rate = (first == labels).float().mean().item()
    second_rate = (second == labels).float().mean().item()
    return {
        "coherence_second": second_rate,
        "coherence_folded_second": second_folded.mean().item(),
        "agreement": (first == second).float().mean().item(),
        "agreement_folded": (fold[first] == fold[second]).float().mean().item(),
        "difference": first_rate - second_rate,
        "difference_folded": (first_folded.mean() - second_folded.mean()).item(),
        "coherence_folded_both": (first_folded * second_folded).mean().item(),
    }


DISAGREEMENT = 0.05
"""A folded coherence whose two classifiers differ by more than this is marked in coherence.md."""


def mark(row: dict | None, key: str) -> str:
    """ " †" after a folded rate on which the two classifiers disagree (:data:`DISAGREEMENT`)."""
    if key != "coherence_folded" or row is None or row.get("difference_folded") is None:
        return ""
    return " †" if abs(row["difference_folded"]) > DISAGREEMENT else ""


def mark_note(rows: list[dict]) -> str:
    if all(r.get("difference_folded") is None for r in rows):
        return ""
    return (
        f" A folded rate marked with † differs from the second classifier's by more than "
        f"{DISAGREEMENT:.2f} (see 'Two classifiers: agreement' below): quote it with the second."
    )


AGREEMENT_NOTE = (
    "Every generated trajectory and image is read by two independently built classifiers "
    "(`prg/evaluation/second_readers.py`): a trajectory by the MLP on its coordinates and by the "
    "image CNN on the trajectory drawn as the dataset draws its images (`traj_rendered`: it "
    "sees the shape, not the order of the points); an image by the CNN and by the nearest "
    "training image on principal components of the pixels (`image_knn`). Each entry: folded "
    "coherence under the first / the second classifier; in brackets the share of samples both "
    "read as the same class (shape twins folded) and the share both read as the true class. "
    "Generated labels need no classifier."
)


def agreement_markdown(
    rows: list[dict],
    title: Callable[[str], str],
    table: Callable[[list[str], list[list[str]]], str],
) -> list[str]:
    """The section of coherence.md that compares the two classifiers.

    Parameters
    ----------
    rows : list of dict
        Coherence rows (:func:`prg.evaluation.run.coherence_rows`).
    title : callable
        Family -> its title in the reports (``PRG_CVAE(T,S)``).
    table : callable
        (header, body rows) -> a Markdown table.

    Returns
    -------
    list of str
        The section's paragraphs; none when no row has a second reading.
    """
    rows = [r for r in rows if r.get("coherence_folded_second") is not None]
    if not rows:
        return []
    kinds = list(dict.fromkeys(r["kind"] for r in rows))
    parts = ["## Two classifiers: agreement", AGREEMENT_NOTE]
    for name in dict.fromkeys(r["model"] for r in rows):
        mine = [r for r in rows if r["model"] == name]
        by_key = {(r["target"], r["given"], r["kind"]): r for r in mine}
        body = []
        for target, given in dict.fromkeys((r["target"], r["given"]) for r in mine):
            star = "*" if LETTER[target] in given.split(",") else ""
            body.append(
                [f"{LETTER[target]} given {{{given}}}{star}"]
                + [_two_readings(by_key.get((target, given, k))) for k in kinds]
            )
        parts += [f"### {name}: {title(mine[0]['family'])}", table(["generated", *kinds], body)]
    return parts


def _two_readings(row: dict | None) -> str:
    if row is None:
        return "-"
    return (
        f"{row['coherence_folded']:.3f} / {row['coherence_folded_second']:.3f} "
        f"(agree {row['agreement_folded']:.2f}, both {row['coherence_folded_both']:.2f})"
    )
