"""A writer's own style from a few letters: does the model's writing pass for that writer's?

Protocol, on the test split's writers (no model saw them), for each seed:

1. ``n_eval`` letter classes E are set aside for scoring.
2. A writer-identification classifier (:func:`writer_features`, then a linear classifier) is
   trained on the real letters of those writers of every class *not* in E.
3. For each writer and each k: k letters of theirs, of classes outside E, are the style
   (:func:`prg.pipeline.hands.match_hand`); the model writes the classes of E in that style
   (:func:`prg.pipeline.hands.components`, :func:`~prg.pipeline.hands.decode_in_hand`); the
   classifier names a writer for each generated letter.

The rate of letters attributed to the right writer is reported beside the classifier's rate on
the writer's own real letters of E (the ceiling) and chance (one over the writers).

The classifier sees features meant to carry a hand, not a letter: the distribution of stroke
directions (slant, roundness), of turning angles, the box's aspect ratio and the stroke's
high-frequency roughness, each centred on its class's mean over the writers (a letter's own
shape is the class mean's part; what is left is the writer's).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from sklearn.linear_model import LogisticRegression
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

from prg.data.hands import HandBank
from prg.evaluation.modes import originals
from prg.models.base import MultimodalVAE
from prg.pipeline.hands import decoder_bias, match_hand, write_in_hand


def writer_features(traj: np.ndarray) -> np.ndarray:
    """Per letter, features of the hand that wrote it.

    Parameters
    ----------
    traj : ndarray, shape (N, 200)
        Normalised letters (interleaved x, y).

    Returns
    -------
    ndarray, shape (N, 30)
        16-bin histogram of segment directions (length-weighted, modulo pi: a stroke up or down
        the same slant counts alike), 8-bin histogram of turning angles, the aspect ratio
        (log width / height), the mean and std of the absolute turning angle, the roughness
        (mean squared second difference over mean squared first difference), the slant (the
        angle of the principal axis) and the path length.
    """
    xy = np.asarray(traj, dtype=np.float64).reshape(len(traj), -1, 2)
    step = np.diff(xy, axis=1)
    length = np.linalg.norm(step, axis=-1)
    angle = np.arctan2(step[..., 1], step[..., 0])
    weights = length / np.maximum(length.sum(1, keepdims=True), 1e-12)
    bins = np.floor((np.mod(angle, np.pi) / np.pi) * 16).astype(int).clip(0, 15)
    directions = np.zeros((len(xy), 16))
    np.add.at(directions, (np.arange(len(xy))[:, None], bins), weights)
    turn = np.angle(np.exp(1j * np.diff(angle, axis=1)))
    turn_bins = np.floor((turn + np.pi) / (2 * np.pi) * 8).astype(int).clip(0, 7)
    turning = np.zeros((len(xy), 8))
    np.add.at(turning, (np.arange(len(xy))[:, None], turn_bins), 1.0 / turn.shape[1])
    span = xy.max(1) - xy.min(1)
    aspect = np.log(np.maximum(span[:, 0], 1e-3) / np.maximum(span[:, 1], 1e-3))
    second = np.diff(xy, 2, axis=1)
    roughness = (second**2).sum((1, 2)) / np.maximum((step**2).sum((1, 2)), 1e-12)
    centred = xy - xy.mean(1, keepdims=True)
    cov = np.einsum("nki,nkj->nij", centred, centred)
    slant = 0.5 * np.arctan2(2 * cov[:, 0, 1], cov[:, 0, 0] - cov[:, 1, 1])
    extra = np.column_stack(
        [aspect, np.abs(turn).mean(1), np.abs(turn).std(1), roughness, slant, length.sum(1)]
    )
    return np.hstack([directions, turning, extra])


def class_centred(
    features: np.ndarray, labels: np.ndarray, means: Mapping[int, np.ndarray]
) -> np.ndarray:
    """``features`` minus their class's mean (``means``: class -> mean feature row)."""
    return features - np.stack([means[int(c)] for c in labels])


def style_rates(
    model: MultimodalVAE,
    bank: HandBank,
    test: Mapping[str, np.ndarray],
    ks: Sequence[int] = (1, 5, 15),
    seeds: Sequence[int] = (0, 1, 2),
    n_eval: int = 12,
    temperature: float = 0.5,
) -> list[dict]:
    """Writer-identification rates of letters generated in held-out writers' styles.

    Returns
    -------
    list of dict
        One row per seed and k: ``seed``, ``k``, ``generated`` (rate of generated letters
        attributed to the right writer), ``real`` (the classifier's rate on the writers' own
        letters of the scored classes), ``chance``, ``writers``, ``letters``.
    """
    traj, labels, writers = originals(test)
    names = sorted(set(writers))
    features = writer_features(traj)
    means = {int(c): features[labels == c].mean(0) for c in np.unique(labels)}
    centred = class_centred(features, labels, means)
    bias = decoder_bias(model, bank)
    rows = []
    for seed in seeds:
        rng = np.random.default_rng(seed)
        scored = rng.choice(np.unique(labels), size=n_eval, replace=False)
        held = np.isin(labels, scored)
        classifier = make_pipeline(StandardScaler(), LogisticRegression(C=0.5, max_iter=5000))
        classifier.fit(centred[~held], writers[~held])
        real_rate = float((classifier.predict(centred[held]) == writers[held]).mean())
        for k in ks:
            right = total = 0
            for w in names:
                mine = np.flatnonzero((writers == w) & ~held)
                classes = np.unique(labels[mine])
                given = rng.choice(classes, size=min(k, len(classes)), replace=False)
                style = np.array([rng.choice(mine[labels[mine] == c]) for c in given])
                hand = match_hand(bank, traj[style], labels[style])
                targets = np.unique(labels[(writers == w) & held])
                letters = write_in_hand(model, bank, hand, targets, temperature, seed, bias)
                x = class_centred(
                    writer_features(letters.reshape(len(targets), -1)), targets, means
                )
                right += int((classifier.predict(x) == w).sum())
                total += len(targets)
            rows.append(
                {
                    "seed": seed,
                    "k": k,
                    "generated": right / total,
                    "real": real_rate,
                    "chance": 1 / len(names),
                    "writers": len(names),
                    "letters": total,
                }
            )
    return rows


def style_summary(rows: list[dict]) -> list[dict]:
    """Per family and k, the means over seeds: ``generated``, ``real``, ``chance`` and
    ``ratio`` (generated over real), with ``generated_sd`` (the seeds' std)."""
    out = []
    keys = dict.fromkeys((r["family"], r["k"]) for r in rows)
    for family, k in keys:
        mine = [r for r in rows if r["family"] == family and r["k"] == k]
        generated = np.array([r["generated"] for r in mine])
        real = np.mean([r["real"] for r in mine])
        out.append(
            {
                "family": family,
                "k": k,
                "generated": float(generated.mean()),
                "generated_sd": float(generated.std(ddof=1)) if len(mine) > 1 else 0.0,
                "real": float(real),
                "chance": mine[0]["chance"],
                "ratio": float(generated.mean() / real) if real > 0 else float("nan"),
                "seeds": len(mine),
            }
        )
    return out
