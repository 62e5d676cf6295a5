"""How alike generated samples are to real ones, measured on flattened trajectory vectors.

Every function takes two float arrays of shape (n, d), one row per sample (a letter's 200
normalised coordinates, say), and returns plain floats:

- :func:`knn_precision_recall`: the k-nearest-neighbour precision and recall of Kynkäänniemi
  et al., "Improved Precision and Recall Metric for Assessing Generative Models" (NeurIPS
  2019). Precision is the share of generated samples that look real (fidelity), recall the
  share of real samples the generator covers (diversity). Both are 1 for identical sets.
- :func:`c2st`: the classifier two-sample test of Lopez-Paz & Oquab, "Revisiting Classifier
  Two-Sample Tests" (ICLR 2017), with a linear classifier: the cross-validated accuracy of
  telling generated from real. 0.5 means the classifier cannot tell them apart, 1 that it
  always can.
- :func:`spread_ratio`: the median pairwise distance among generated samples over the same
  among real ones. Below 1 the generator is less varied than the data (1 is ideal).

:func:`likeness` averages the four numbers over the classes present in both sets.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from scipy.spatial.distance import cdist, pdist
from sklearn.linear_model import LogisticRegression
from sklearn.model_selection import StratifiedKFold
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler


def _rows(x: np.ndarray, name: str, min_rows: int) -> np.ndarray:
    """``x`` as a finite float array of shape (n, d) with n >= ``min_rows``, else ValueError."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 2:
        raise ValueError(f"{name} must have shape (n, d), got shape {x.shape}")
    if len(x) < min_rows:
        raise ValueError(f"{name} needs at least {min_rows} rows, got {len(x)}")
    if not np.isfinite(x).all():
        raise ValueError(f"{name} contains NaN or infinite values")
    return x


def _pair(real: np.ndarray, generated: np.ndarray, min_rows: int) -> tuple[np.ndarray, np.ndarray]:
    real, generated = _rows(real, "real", min_rows), _rows(generated, "generated", min_rows)
    if real.shape[1] != generated.shape[1]:
        raise ValueError(f"generated has {generated.shape[1]} columns, real has {real.shape[1]}")
    return real, generated


def _coverage(centres: np.ndarray, queries: np.ndarray, k: int) -> float:
    """Share of ``queries`` (m, d) inside the k-NN manifold of ``centres`` (n, d)."""
    # Column k of each sorted row of distances is the k-th neighbour, column 0 being the point
    # itself (distance 0). cdist computes both matrices the same exact way, so an identical
    # point is at distance 0 and a point on a ball's boundary counts as inside.
    radii = np.partition(cdist(centres, centres), k, axis=1)[:, k]
    return float((cdist(queries, centres) <= radii).any(axis=1).mean())


def knn_precision_recall(
    real: np.ndarray, generated: np.ndarray, k: int = 3
) -> tuple[float, float]:
    """k-NN precision and recall (Kynkäänniemi et al. 2019).

    Each set's manifold is the union of balls centred on its points, each ball's radius the
    distance from its centre to the centre's k-th nearest neighbour in the same set.

    Parameters
    ----------
    real : ndarray, shape (n, d)
        Real samples, n > k.
    generated : ndarray, shape (m, d)
        Generated samples, m > k.
    k : int
        Neighbour whose distance sets each ball's radius.

    Returns
    -------
    precision : float
        Share of generated samples inside the real manifold, in [0, 1].
    recall : float
        Share of real samples inside the generated manifold, in [0, 1].

    Examples
    --------
    >>> x = np.random.default_rng(0).normal(size=(50, 2))
    >>> knn_precision_recall(x, x, k=3)
    (1.0, 1.0)
    >>> knn_precision_recall(x, x + 100.0, k=3)
    (0.0, 0.0)
    """
    real, generated = _pair(real, generated, k + 1)
    return _coverage(real, generated, k), _coverage(generated, real, k)


def c2st(real: np.ndarray, generated: np.ndarray, folds: int = 5, seed: int = 0) -> float:
    """Classifier two-sample test (Lopez-Paz & Oquab 2017) with a linear classifier.

    A standardised logistic regression learns to tell generated (class 1) from real (class 0)
    rows; the score is its mean accuracy over stratified cross-validation folds (balanced
    accuracy when the sets differ in size, so that guessing the larger set scores 0.5).

    Parameters
    ----------
    real : ndarray, shape (n, d)
        Real samples, n >= 2.
    generated : ndarray, shape (m, d)
        Generated samples, m >= 2.
    folds : int
        Cross-validation folds, reduced to min(n, m) when that is smaller (at least 2).
    seed : int
        Seed of the fold shuffle.

    Returns
    -------
    float
        Held-out accuracy in [0, 1]: about 0.5 when the sets are indistinguishable.

    Examples
    --------
    >>> x = np.random.default_rng(0).normal(size=(100, 5))
    >>> c2st(x, x + 10.0)
    1.0
    """
    real, generated = _pair(real, generated, 2)
    x = np.concatenate([real, generated])
    y = np.concatenate([np.zeros(len(real), dtype=int), np.ones(len(generated), dtype=int)])
    splits = StratifiedKFold(
        n_splits=max(2, min(folds, len(real), len(generated))), shuffle=True, random_state=seed
    )
    # liblinear: the same fit as lbfgs on these small binary problems, four times faster
    model = make_pipeline(
        StandardScaler(), LogisticRegression(C=1.0, solver="liblinear", max_iter=5000)
    )
    scores = []
    for train, held in splits.split(x, y):
        predicted = model.fit(x[train], y[train]).predict(x[held])
        # balanced accuracy: the mean of the two classes' recalls (plain accuracy when the
        # held-out fold is balanced); written out, as sklearn's scorer costs more than the fit
        recalls = [(predicted[y[held] == c] == c).mean() for c in (0, 1)]
        hits = (predicted == y[held]).mean()
        scores.append(hits if len(real) == len(generated) else np.mean(recalls))
    return float(np.mean(scores))


def spread_ratio(real: np.ndarray, generated: np.ndarray) -> float:
    """Median pairwise Euclidean distance within ``generated`` over that within ``real``.

    Parameters
    ----------
    real : ndarray, shape (n, d)
        Real samples, n >= 2, not all equal.
    generated : ndarray, shape (m, d)
        Generated samples, m >= 2.

    Returns
    -------
    float
        1 when both sets are equally spread out, 0 when all generated samples are equal.

    Examples
    --------
    >>> x = np.random.default_rng(0).normal(size=(20, 3))
    >>> spread_ratio(x, 0.5 * x)
    0.5
    """
    real, generated = _pair(real, generated, 2)
    scale = float(np.median(pdist(real)))
    if scale == 0.0:
        raise ValueError("real has median pairwise distance 0, so there is nothing to compare to")
    return float(np.median(pdist(generated))) / scale


def likeness(
    real_by_class: Mapping[int, np.ndarray],
    generated_by_class: Mapping[int, np.ndarray],
    k: int = 3,
    seed: int = 0,
) -> dict[str, float]:
    """The four measures, each averaged over the classes present in both mappings.

    Parameters
    ----------
    real_by_class : mapping of int to ndarray, shape (n_c, d)
        Real samples of each class.
    generated_by_class : mapping of int to ndarray, shape (m_c, d)
        Generated samples of each class.
    k : int
        Neighbour of :func:`knn_precision_recall`; classes where either set has <= k rows
        are skipped.
    seed : int
        Seed of :func:`c2st`'s folds.

    Returns
    -------
    dict of str to float
        Mean ``"precision"``, ``"recall"``, ``"c2st"`` and ``"spread"``, and ``"classes"``,
        the number of classes averaged over.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> real = {0: rng.normal(size=(30, 2)), 1: rng.normal(size=(30, 2)), 2: np.zeros((2, 2))}
    >>> out = likeness(real, {0: real[0], 1: real[1] + 100.0, 2: np.zeros((9, 2))})
    >>> out["classes"], out["precision"], out["recall"]
    (2.0, 0.5, 0.5)
    """
    rows: list[tuple[float, float, float, float]] = []
    for c in sorted(set(real_by_class) & set(generated_by_class)):
        real, generated = real_by_class[c], generated_by_class[c]
        if len(real) <= k or len(generated) <= k:
            continue
        precision, recall = knn_precision_recall(real, generated, k)
        rows.append(
            (precision, recall, c2st(real, generated, seed=seed), spread_ratio(real, generated))
        )
    if not rows:
        raise ValueError(f"no class has more than k={k} rows in both real and generated samples")
    means = np.mean(rows, axis=0)
    names = ("precision", "recall", "c2st", "spread")
    return {**{n: float(v) for n, v in zip(names, means)}, "classes": float(len(rows))}
