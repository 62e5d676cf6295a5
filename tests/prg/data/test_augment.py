"""Tests of the class-balanced sigma-lognormal augmentation."""

from __future__ import annotations

import json

import numpy as np
import pytest

from prg.data import sigma_lognormal as sl
from prg.data.augment import (
    AugmentResult,
    AugmentSettings,
    augment,
    fit_quality_summary,
    fit_trajectory,
)
from prg.data.preprocess import ImageSettings, PreprocessSettings, normalise, resample_arclength
from prg.data.synthetic import SyntheticSettings
from prg.errors import SettingsError, UsageError
from tests.conftest import writer_variation

# ----------------------------------------------------------------------------------------------
# Ten letter-like classes, several jittered "writers" each (made here, no data generator)
# ----------------------------------------------------------------------------------------------


def _polyline(corners, u):
    pts = np.asarray(corners, dtype=float)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    s /= s[-1]
    return np.column_stack([np.interp(u, s, pts[:, 0]), np.interp(u, s, pts[:, 1])])


def _arc(u, start, stop, radius=1.0):
    a = start + u * (stop - start)
    return np.column_stack([radius * np.cos(a), radius * np.sin(a)])


CLASSES = {
    "c": lambda u: _arc(u, np.pi / 4, 7 * np.pi / 4),
    "s": lambda u: np.column_stack([0.5 * np.sin(2 * np.pi * u), np.cos(np.pi * u)]),
    "v": lambda u: _polyline([(-1, 1), (0, -1), (1, 1)], u),
    "z": lambda u: _polyline([(-1, 1), (1, 1), (-1, -1), (1, -1)], u),
    "w": lambda u: _polyline([(-1, 1), (-0.5, -1), (0, 0.5), (0.5, -1), (1, 1)], u),
    "spiral": lambda u: _arc(u, 0.0, 4 * np.pi, 0.2 + 0.8 * u),
    "1": lambda u: _polyline([(-0.4, 0.6), (0.1, 1.0), (0.1, -1.0)], u),
    "l": lambda u: np.column_stack(
        [0.3 * np.sin(2 * np.pi * u) + 0.2 * u, 0.6 * (1 - np.cos(2 * np.pi * u))]
    ),
    "7": lambda u: _polyline([(-1, 1), (1, 1), (-0.2, -1)], u),
    "n": lambda u: np.vstack(
        [
            _polyline([(-1, -1), (-1, 0.2)], np.linspace(0, 1, 60)),
            _arc(np.linspace(0, 1, 100), np.pi, 0.0, 1.0) * [1.0, 0.8] + [0.0, 0.2],
            _polyline([(1, 0.2), (1, -1)], np.linspace(0, 1, 60)),
        ]
    ),
}


def _jittered(name: str, rng: np.random.Generator, amount: float = 0.07) -> np.ndarray:
    u = np.linspace(0.0, 1.0, 400)
    return writer_variation(CLASSES[name](u), u, rng, amount)


def dataset(per_class: int = 4, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    trajs, labels = [], []
    for label, name in enumerate(CLASSES):
        for _ in range(per_class):
            trajs.append(_jittered(name, rng))
            labels.append(label)
    return np.stack(trajs), np.array(labels)


@pytest.fixture(scope="module")
def data():
    return dataset()


@pytest.fixture(scope="module")
def result(data):
    trajs, labels = data
    return augment(
        trajs, labels, AugmentSettings(per_class=30), seed=123, workers=1, progress=False
    )


# ----------------------------------------------------------------------------------------------


def test_output_is_class_balanced_and_well_formed(data, result):
    trajs, labels = data
    n_classes = len(CLASSES)
    assert isinstance(result, AugmentResult)
    assert result.trajectories.shape == (30 * n_classes, 100, 2)
    assert result.trajectories.dtype == np.float32
    assert np.all(np.isfinite(result.trajectories))
    np.testing.assert_allclose(np.abs(result.trajectories).max(axis=(1, 2)), 1.0, rtol=1e-6)
    np.testing.assert_allclose(result.trajectories.mean(axis=1), 0.0, atol=1e-5)
    steps = np.linalg.norm(np.diff(result.trajectories, axis=1), axis=2)
    # equidistant along the arc: equal chords except across sharp corners and cusps
    deviation = np.abs(steps / np.median(steps, axis=1, keepdims=True) - 1.0)
    assert np.mean(deviation < 0.02) > 0.95
    assert result.labels.shape == result.parent.shape == (30 * n_classes,)
    assert result.parent.dtype == np.int64 and result.parent.min() >= 0
    np.testing.assert_array_equal(labels[result.parent], result.labels)
    counts = np.bincount(result.labels, minlength=n_classes)
    np.testing.assert_array_equal(counts, np.full(n_classes, 30))
    # round-robin over the parents: each original of a class is used equally often (4 x 7 or 8)
    used = np.bincount(result.parent, minlength=trajs.shape[0])
    assert used.min() >= 30 // 4 - 1 and used.max() <= 30 // 4 + 1
    # originals are not in the output
    for row, parent in enumerate(result.parent[:20]):
        assert not np.allclose(result.trajectories[row], trajs[parent], atol=1e-4)


def test_stats_are_complete_and_json_serialisable(result):
    stats = result.stats
    for key in (
        "n_fits",
        "n_fitted",
        "n_failed",
        "failure_rate",
        "snr_db_mean",
        "snr_db_median",
        "snr_db_p10",
        "components_mean",
        "fit_seconds",
        "fit_seconds_mean",
        "n_generated",
        "n_copied",
        "n_redraws",
        "classes_copied",
    ):
        assert key in stats
    assert json.loads(json.dumps(stats)) == stats
    assert stats["n_fits"] == 40 and stats["n_generated"] == 300
    assert stats["n_fitted"] + stats["n_failed"] == 40
    assert stats["failure_rate"] <= 0.1
    assert stats["snr_db_median"] >= 20.0
    assert all(isinstance(v, int | float) for v in stats.values())


def test_reproducible_by_seed_and_independent_of_workers(data, result):
    trajs, labels = data
    again = augment(
        trajs, labels, AugmentSettings(per_class=30), seed=123, workers=1, progress=False
    )
    np.testing.assert_array_equal(again.trajectories, result.trajectories)
    np.testing.assert_array_equal(again.parent, result.parent)
    parallel = augment(
        trajs, labels, AugmentSettings(per_class=30), seed=123, workers=2, progress=False
    )
    np.testing.assert_array_equal(parallel.trajectories, result.trajectories)
    np.testing.assert_array_equal(parallel.labels, result.labels)
    np.testing.assert_array_equal(parallel.parent, result.parent)
    other = augment(
        trajs, labels, AugmentSettings(per_class=30), seed=124, workers=1, progress=False
    )
    assert not np.array_equal(other.trajectories, result.trajectories)


def test_augmented_samples_are_still_recognisable(data, result):
    trajs, labels = data
    flat = trajs.reshape(len(trajs), -1)
    samples = result.trajectories.reshape(len(result.labels), -1).astype(np.float64)
    dist = ((samples[:, None, :] - flat[None, :, :]) ** 2).sum(axis=2)  # (M, N)
    predicted = labels[np.argmin(dist, axis=1)]  # 1-nearest-neighbour among the originals
    accuracy = float(np.mean(predicted == result.labels))
    assert accuracy >= 0.9, accuracy
    # and they vary: samples differ from their parent by more than float noise
    gap = np.linalg.norm(result.trajectories - trajs[result.parent], axis=2).mean(axis=1)
    assert np.median(gap) > 0.02


def test_failed_fits_are_not_parents_unless_the_class_has_no_fit(data):
    trajs, _ = data
    dead = np.zeros((1, 100, 2))  # a zero-extent stroke: its fit fails
    sub = np.concatenate([trajs[:4], dead, trajs[4:5]])  # class 0: 4 good + 1 dead; class 1: 1
    sub_labels = np.array([0, 0, 0, 0, 0, 1])
    out = augment(sub, sub_labels, AugmentSettings(per_class=9), seed=1, workers=1, progress=False)
    assert 4 not in set(out.parent.tolist())
    assert out.stats["n_failed"] == 1 and out.stats["classes_copied"] == 0
    # With an unreachable target nothing fits: every class is copied round-robin, unchanged.
    copied = augment(
        sub,
        sub_labels,
        AugmentSettings(per_class=7, snr_target_db=400.0),
        seed=1,
        workers=1,
        progress=False,
    )
    assert copied.stats["classes_copied"] == 2 and copied.stats["n_copied"] == 14
    np.testing.assert_array_equal(copied.parent[:7], [0, 1, 2, 3, 4, 0, 1])
    np.testing.assert_array_equal(copied.trajectories, sub[copied.parent].astype(np.float32))


def test_zero_perturbation_reproduces_the_fits(data):
    trajs, labels = data
    out = augment(
        trajs[:3],
        labels[:3],
        AugmentSettings(per_class=3, amplitude=0.0, rotation_deg=0.0, sweep=0.0),
        seed=0,
        workers=1,
        progress=False,
    )
    for row, parent in enumerate(out.parent):
        fit, t = fit_trajectory(trajs[parent])
        dense = np.interp(np.linspace(0, 99, 397), np.arange(100), t)
        expect = normalise(resample_arclength(sl.trajectory(fit.params, dense, fit.start), 100))
        np.testing.assert_allclose(out.trajectories[row], expect, atol=1e-6)


def test_empty_and_invalid_inputs(data):
    trajs, labels = data
    empty = augment(
        trajs[:0], labels[:0], AugmentSettings(per_class=5), seed=0, workers=2, progress=False
    )
    assert empty.trajectories.shape == (0, 100, 2) and empty.parent.shape == (0,)
    none = augment(
        trajs[:2], labels[:2], AugmentSettings(per_class=0), seed=0, workers=1, progress=False
    )
    assert none.trajectories.shape[0] == 0
    with pytest.raises(UsageError):
        augment(trajs[:, :, 0], labels, AugmentSettings(per_class=1), seed=0)
    with pytest.raises(UsageError):
        augment(trajs, labels[:-1], AugmentSettings(per_class=1), seed=0)
    with pytest.raises(UsageError):
        augment(trajs, labels, AugmentSettings(per_class=-1), seed=0)
    with pytest.raises(UsageError):
        augment(trajs, labels, AugmentSettings(per_class=1, amplitude=1.5), seed=0)
    bad = trajs.copy()
    bad[0, 0, 0] = np.nan
    with pytest.raises(UsageError):
        augment(bad, labels, AugmentSettings(per_class=1), seed=0)


def test_fit_quality_summary():
    ok = sl.FitResult(np.zeros((2, 6)), np.zeros(2), 25.0, 2, True, "")
    bad = sl.FitResult(np.zeros((15, 6)), np.zeros(2), 10.0, 15, False, "")
    summary = fit_quality_summary([ok, ok, ok, bad])
    assert summary["n_fits"] == 4 and summary["n_fitted"] == 3 and summary["n_failed"] == 1
    assert summary["failure_rate"] == 0.25
    assert summary["snr_db_median"] == 25.0 and summary["snr_db_mean"] == pytest.approx(21.25)
    assert summary["components_mean"] == pytest.approx(5.25)
    assert fit_quality_summary([])["failure_rate"] == 0.0


@pytest.mark.parametrize(
    "make, field",
    [
        (lambda: PreprocessSettings(n_points=1), "n_points"),
        (lambda: ImageSettings(size=3), "size"),
        (lambda: AugmentSettings(per_class=-1), "per_class"),
        (lambda: AugmentSettings(snr_target_db="high"), "snr_target_db"),
        (lambda: SyntheticSettings(n_writers=0), "n_writers"),
        (lambda: SyntheticSettings(fonts=("comic",)), "fonts"),
    ],
)
def test_settings_classes_name_the_field_not_a_config_path(make, field):
    with pytest.raises(SettingsError) as caught:
        make()
    assert caught.value.field == field and str(caught.value).startswith(f"{field} ")
