"""Tests of prg.evaluation.likeness: cases whose answer is known without running the code."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from prg.evaluation.likeness import c2st, knn_precision_recall, likeness, spread_ratio


def _gauss(seed: int, n: int = 200, d: int = 10, shift: float = 0.0) -> np.ndarray:
    return np.random.default_rng(seed).normal(size=(n, d)) + shift


def test_identical_sets_match_perfectly():
    x = _gauss(0)
    assert knn_precision_recall(x, x.copy(), k=3) == (1.0, 1.0)
    assert spread_ratio(x, x.copy()) == 1.0


def test_c2st_is_near_chance_on_two_draws_of_one_gaussian():
    assert abs(c2st(_gauss(1), _gauss(2)) - 0.5) <= 0.15


def test_c2st_uses_balanced_accuracy_for_unequal_sizes():
    # 200 real vs 50 generated from one distribution: always answering "real" would score 0.8
    # plain accuracy, but balanced accuracy stays at chance.
    assert abs(c2st(_gauss(3, n=200), _gauss(4, n=50)) - 0.5) <= 0.15


def test_disjoint_sets_share_nothing():
    real, generated = _gauss(5), _gauss(6, shift=20.0)
    assert knn_precision_recall(real, generated) == (0.0, 0.0)
    assert c2st(real, generated) > 0.95


def test_c2st_detects_a_shift():
    real = _gauss(7)
    same, shifted = c2st(real, _gauss(8)), c2st(real, _gauss(8, shift=0.5))
    assert shifted > same + 0.2
    # The best possible accuracy is Phi(|mean shift| / 2) = Phi(0.5 * sqrt(10) / 2) ~ 0.785.
    assert 0.7 < shifted < 0.85


def _core_and_cloud() -> tuple[np.ndarray, np.ndarray]:
    """500 points of a 2-d standard Gaussian and its rows within radius 0.5 of the origin."""
    cloud = np.random.default_rng(9).normal(size=(500, 2))
    core = cloud[np.linalg.norm(cloud, axis=1) < 0.5]
    assert len(core) > 20  # about 12 % of the cloud
    return cloud, core


def test_a_subset_is_precise_but_does_not_recall_everything():
    cloud, core = _core_and_cloud()
    precision, recall = knn_precision_recall(cloud, core)
    # Every core point is a centre of the real manifold, at distance 0 from itself.
    assert precision == 1.0
    # The core's balls stay near radius 0.5, while about 61 % of the cloud (P(|x| > 1) =
    # exp(-1/2) in 2-d) lies beyond radius 1.
    assert recall < 0.6


def test_a_superset_recalls_everything_but_is_not_precise():
    cloud, core = _core_and_cloud()
    precision, recall = knn_precision_recall(core, cloud)
    assert recall == 1.0
    assert precision < 0.6


def test_hand_computed_one_dimensional_case():
    # k = 1, so each radius is the distance to the nearest other point of the same set.
    # real      -3   0   1   3     radii 3, 1, 1, 2  -> manifold [-6, 0] u [-1, 1] u [0, 2] u [1, 5]
    # generated 2.5  5  5.5  10    radii 2.5, .5, .5, 4.5
    #                              -> manifold [0, 5] u [4.5, 5.5] u [5, 6] u [5.5, 14.5]
    # precision: 2.5 in, 5 in (|5 - 3| = 2, on real ball's boundary), 5.5 out, 10 out -> 2/4
    # recall: -3 out, 0 in (|0 - 2.5| = 2.5, on the boundary), 1 in, 3 in -> 3/4
    real = np.array([[-3.0], [0.0], [1.0], [3.0]])
    generated = np.array([[2.5], [5.0], [5.5], [10.0]])
    assert knn_precision_recall(real, generated, k=1) == (0.5, 0.75)


def test_precision_and_recall_swap_with_the_sets():
    a, b = _gauss(10, n=60), _gauss(11, n=80, shift=0.7)
    assert_array_equal(knn_precision_recall(a, b), knn_precision_recall(b, a)[::-1])


def test_spread_of_a_half_scaled_copy_is_one_half():
    x = _gauss(12, n=40)
    # Scaling by a power of two is exact in floating point, so the ratio is exactly 0.5.
    assert spread_ratio(x, 0.5 * x) == 0.5
    assert_allclose(spread_ratio(x, 3.0 * x), 3.0, rtol=1e-12)


def test_spread_of_equal_generated_points_is_zero():
    assert spread_ratio(_gauss(13), np.ones((30, 10))) == 0.0


def _with_nan(x: np.ndarray) -> np.ndarray:
    x[len(x) // 2, 0] = np.nan
    return x


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: knn_precision_recall(np.zeros((3, 2)), _gauss(0, d=2), k=3), "real"),
        (lambda: knn_precision_recall(_gauss(0, d=2), np.zeros((3, 2)), k=3), "generated"),
        (lambda: knn_precision_recall(_gauss(0, d=2), _gauss(1, d=3)), "generated"),
        (lambda: knn_precision_recall(np.zeros(10), _gauss(1, d=3)), "real"),
        (lambda: knn_precision_recall(_with_nan(_gauss(0, d=1)), _gauss(1, d=1)), "real"),
        (lambda: c2st(_gauss(0), np.full((20, 10), np.inf)), "generated"),
        (lambda: c2st(_gauss(0), _gauss(1)[:1]), "generated"),
        (lambda: spread_ratio(np.ones((5, 10)), _gauss(1)), "real"),
        (lambda: spread_ratio(_gauss(0), _gauss(1, d=4)), "generated"),
    ],
)
def test_bad_inputs_name_the_argument(call, name):
    with pytest.raises(ValueError, match=name):
        call()


def test_likeness_averages_over_shared_classes_and_skips_tiny_ones():
    same, near, far = _gauss(14, n=40, d=4), _gauss(15, n=40, d=4), _gauss(16, n=40, d=4)
    real = {0: same, 1: near, 2: _gauss(17, n=3, d=4), 3: _gauss(18, n=40, d=4)}
    generated = {0: same.copy(), 1: far + 50.0, 2: _gauss(19, n=40, d=4), 4: far}
    out = likeness(real, generated, k=3, seed=0)
    # Class 2 has only k = 3 real rows, classes 3 and 4 are each in one mapping only.
    assert out["classes"] == 2.0
    # Class 0 is identical (1, 1), class 1 disjoint (0, 0).
    assert out["precision"] == 0.5
    assert out["recall"] == 0.5
    expected_c2st = (c2st(same, same, seed=0) + c2st(near, far + 50.0, seed=0)) / 2
    assert_allclose(out["c2st"], expected_c2st)
    expected_spread = (1.0 + spread_ratio(near, far + 50.0)) / 2
    assert_allclose(out["spread"], expected_spread)


def test_likeness_without_a_usable_class_raises():
    with pytest.raises(ValueError, match="no class"):
        likeness({0: _gauss(0, n=3)}, {0: _gauss(1, n=30), 1: _gauss(2, n=30)}, k=3)
