"""`prg.evaluation.smoothness`: roughness of a trajectory and the roughness ratio."""

import numpy as np
import pytest

from prg.evaluation.smoothness import median_roughness, roughness, roughness_ratio


def _line(n=100):
    t = np.linspace(0.0, 1.0, n)
    return np.stack([0.3 + 1.7 * t, -0.2 + 0.9 * t], axis=-1)  # (n, 2), equidistant points


def _arc(n=100, radius=1.0, sweep=np.pi):
    phi = np.linspace(0.0, sweep, n)
    return radius * np.stack([np.cos(phi), np.sin(phi)], axis=-1)


def test_a_straight_line_has_no_roughness():
    assert roughness(_line()) == pytest.approx(0.0, abs=1e-12)


def test_a_circular_arc_matches_its_closed_form():
    """n equidistant points on a circle, step angle theta: every second difference has length
    2 R (1 - cos theta), every step 2 R sin(theta / 2), so the roughness is
    (n - 2) / (n - 1) * 2 sin(theta / 2), whatever the radius."""
    n, sweep = 100, 1.5 * np.pi
    theta = sweep / (n - 1)
    expected = (n - 2) / (n - 1) * 2 * np.sin(theta / 2)
    assert roughness(_arc(n, 3.0, sweep)) == pytest.approx(expected, rel=1e-9)


def test_noise_raises_roughness_and_more_noise_raises_it_more():
    rng = np.random.default_rng(0)
    smooth = _arc()
    values = [
        roughness(smooth + level * rng.standard_normal(smooth.shape))
        for level in (0.0, 0.002, 0.01, 0.05)
    ]
    assert values == sorted(values)
    assert values[1] > 1.5 * values[0]
    assert values[3] > 10 * values[0]


def test_scale_translation_and_rotation_do_not_change_it():
    rng = np.random.default_rng(1)
    letter = np.cumsum(rng.standard_normal((100, 2)), axis=0)
    angle = 0.7
    rotation = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    moved = 12.5 * letter @ rotation.T + np.array([3.0, -40.0])
    assert roughness(moved) == pytest.approx(roughness(letter), rel=1e-9)
    assert roughness(1e-4 * letter) == pytest.approx(roughness(letter), rel=1e-9)


def test_a_trajectory_with_no_length_is_nan():
    assert np.isnan(roughness(np.full((100, 2), 0.4)))
    assert np.isnan(roughness(np.zeros(200)))


def test_interleaved_and_point_layouts_agree_over_a_batch():
    rng = np.random.default_rng(2)
    points = np.cumsum(rng.standard_normal((5, 100, 2)), axis=1)
    flat = points.reshape(5, 200)  # x1, y1, x2, y2, ...
    got = roughness(flat)
    assert got.shape == (5,)
    np.testing.assert_allclose(got, [roughness(p) for p in points], rtol=1e-12)


def test_median_skips_letters_with_no_length():
    batch = np.stack([_arc(), _arc(sweep=0.5 * np.pi), np.zeros((100, 2))])
    values = roughness(batch)
    assert np.isnan(values[2])
    assert median_roughness(batch) == pytest.approx(np.median(values[:2]))
    assert np.isnan(median_roughness(np.zeros((3, 200))))


def test_ratio_is_one_for_the_same_letters_and_grows_with_noise():
    rng = np.random.default_rng(3)
    reference = np.stack([_arc(sweep=s) for s in np.linspace(1.0, 5.0, 9)])
    assert roughness_ratio(reference, reference) == pytest.approx(1.0)
    noisy = reference + 0.02 * rng.standard_normal(reference.shape)
    assert roughness_ratio(noisy, reference) > 2.0
    assert roughness_ratio(reference, noisy) < 0.5


def test_ratio_against_straight_or_empty_references_is_nan():
    exact_line = np.stack([np.arange(100.0), 2.0 * np.arange(100.0)], axis=-1)  # roughness 0
    assert roughness(exact_line) == 0.0
    assert np.isnan(roughness_ratio(_arc()[None], exact_line[None]))
    assert np.isnan(roughness_ratio(_arc()[None], np.zeros((1, 200))))
