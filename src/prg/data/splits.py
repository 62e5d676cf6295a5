"""Writer-disjoint train/validation/test splits."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from prg.errors import UsageError

SPLITS: tuple[str, ...] = ("train", "val", "test")


def split_writers(
    writers: Sequence[str], fractions: Mapping[str, float], seed: int
) -> dict[str, list[str]]:
    """Assign each writer to exactly one split.

    Parameters
    ----------
    writers : sequence of str
        Writer ids (duplicates allowed; one entry per sample is fine).
    fractions : mapping
        ``{"train": f, "val": f, "test": f}``, non-negative, summing to 1 (within 1e-6).
    seed : int
        Shuffles the sorted writer list, so the assignment depends only on the set and the seed.

    Returns
    -------
    dict
        Split name -> sorted writer ids. ``val`` and ``test`` get ``round(f * W)`` writers
        (at least one each when their fraction is positive and there are enough writers);
        ``train`` gets the rest.
    """
    unknown = set(fractions) - set(SPLITS)
    if unknown:
        raise UsageError(f"data.splits has unknown split(s) {sorted(unknown)}: accepted {SPLITS}")
    values = {s: float(fractions.get(s, 0.0)) for s in SPLITS}
    if not all(0 <= v <= 1 for v in values.values()) or abs(sum(values.values()) - 1) > 1e-6:
        raise UsageError(f"data.splits fractions must be >= 0 and sum to 1, got {values}")
    unique = sorted(set(writers))
    n = len(unique)
    needed = 1 + sum(values[s] > 0 for s in ("val", "test"))
    if n < needed:
        raise UsageError(f"{n} writer(s) cannot make writer-disjoint splits {values}")
    order = np.random.default_rng(seed).permutation(n)
    shuffled = [unique[i] for i in order]
    sizes = {s: max(round(values[s] * n), int(values[s] > 0)) for s in ("val", "test")}
    sizes["train"] = n - sizes["val"] - sizes["test"]
    if sizes["train"] < 1:
        raise UsageError(f"data.splits leaves no training writer out of {n}: {values}")
    out, start = {}, 0
    for s in ("test", "val", "train"):
        out[s] = sorted(shuffled[start : start + sizes[s]])
        start += sizes[s]
    return {s: out[s] for s in SPLITS}
