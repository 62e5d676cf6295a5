import numpy as np
import pytest
from numpy.testing import assert_allclose

from prg.data.preprocess import (
    flip_y,
    normalise,
    preprocess_stroke,
    render,
    render_batch,
    resample_arclength,
    smooth,
)
from prg.errors import UsageError
from tests.conftest import letter_like


def _arc_positions(points, polyline):
    """Arc-length position of each point along ``polyline``, walking forward monotonically."""
    cum = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(polyline, axis=0), axis=1))])
    positions, seg = [], 0
    for p in points:
        while True:
            a, b = polyline[seg], polyline[seg + 1]
            ab = b - a
            t = np.clip((p - a) @ ab / max(ab @ ab, 1e-300), 0, 1)
            if np.linalg.norm(a + t * ab - p) < 1e-9 * (1 + np.abs(polyline).max()):
                positions.append(cum[seg] + t * np.sqrt(ab @ ab))
                break
            seg += 1  # raises IndexError if the point is not on the polyline
    return np.array(positions)


@pytest.mark.parametrize("seed", range(6))
def test_resampling_is_equidistant_along_the_arc_and_keeps_endpoints(seed):
    rng = np.random.default_rng(seed)
    raw = letter_like(rng, n=int(rng.integers(6, 300)))  # coarse polylines with corners too
    out = resample_arclength(raw, 100)
    assert out.shape == (100, 2)
    steps = np.diff(_arc_positions(out, raw))
    assert np.abs(steps / steps.mean() - 1).max() < 0.01
    assert_allclose(out[0], raw[0])
    assert_allclose(out[-1], raw[-1])


@pytest.mark.parametrize("seed", range(3))
def test_resampling_a_smooth_curve_gives_equal_chords(seed):
    t = np.linspace(0, 4.5, 2000)  # ellipse arcs: smooth, no cusp
    raw = np.column_stack([np.cos(t) * (1 + seed), np.sin(t)])
    steps = np.linalg.norm(np.diff(resample_arclength(raw, 100), axis=0), axis=1)
    assert np.abs(steps / steps.mean() - 1).max() < 0.01


def test_resampling_tolerates_repeated_points():
    pts = np.array([[0, 0], [0, 0], [1, 0], [1, 0], [1, 1]], dtype=float)
    out = resample_arclength(pts, 5)
    assert_allclose(out, [[0, 0], [0.5, 0], [1, 0], [1, 0.5], [1, 1]])


@pytest.mark.parametrize(
    "bad, match",
    [
        (np.zeros((5, 2)), "zero arc length"),
        (np.zeros((1, 2)), "at least 2"),
        (np.zeros((5, 3)), "shape"),
        (np.array([[0, 0], [np.nan, 1]]), "NaN"),
    ],
)
def test_resampling_rejects_bad_points(bad, match):
    with pytest.raises(UsageError, match=match):
        resample_arclength(bad, 10)


def test_normalise_centres_and_scales_keeping_aspect():
    pts = np.array([[0, 0], [4, 0], [4, 2], [0, 2]], dtype=float) + 7
    out = normalise(pts)
    assert_allclose(out.mean(axis=0), 0, atol=1e-12)
    assert np.abs(out).max() == pytest.approx(1.0)
    width, height = np.ptp(out, axis=0)
    assert width / height == pytest.approx(2.0)


def test_smooth_keeps_endpoints_and_reduces_roughness():
    rng = np.random.default_rng(0)
    t = np.linspace(0, 1, 200)
    noisy = np.column_stack([t, np.sin(3 * t)]) + rng.normal(0, 0.01, (200, 2))
    out = smooth(noisy, 3.0)
    assert_allclose(out[[0, -1]], noisy[[0, -1]])
    rough = lambda p: np.abs(np.diff(p, 2, axis=0)).sum()  # noqa: E731
    assert rough(out) < 0.2 * rough(noisy)


def test_preprocess_flips_y_down_sources():
    stroke = np.array([[0, 0], [0, 10]], dtype=float)  # drawn downwards on a tablet
    out = preprocess_stroke(stroke, n_points=10, smooth_sigma=0)
    assert out[0, 1] > out[-1, 1]  # y up: the pen went down
    assert_allclose(flip_y(flip_y(stroke)), stroke)


def test_render_range_ink_and_centring():
    rng = np.random.default_rng(1)
    traj = normalise(resample_arclength(letter_like(rng), 100))
    img = render(traj)
    assert img.shape == (28, 28) and img.dtype == np.float32
    assert img.min() >= 0 and img.max() <= 1 and img.max() == 1.0
    rows, cols = np.nonzero(img > 0)
    # the ink's bounding box is centred within a pixel and respects the margin
    assert abs((rows.min() + rows.max()) / 2 - 13.5) <= 1.0
    assert abs((cols.min() + cols.max()) / 2 - 13.5) <= 1.0
    assert rows.min() >= 1 and cols.min() >= 1 and rows.max() <= 26 and cols.max() <= 26


def test_render_keeps_aspect_ratio_and_orientation():
    line = np.column_stack([np.linspace(-1, 1, 50), np.full(50, 0.5)])  # horizontal
    img = render(line)
    rows, cols = np.nonzero(img > 0.5)
    assert np.ptp(cols) > 15 and np.ptp(rows) <= 2
    up = np.array([[0.0, 0.0], [0.0, 1.0], [0.6, 1.0]])  # an L upside down: bar at the top
    img = render(up)
    top, bottom = img[:10].sum(), img[-10:].sum()
    assert top > bottom


def _exact_render(points, size=28, width=2.0, margin=2.0):
    """Brute force: distance of every pixel centre to every segment."""
    from prg.data.preprocess import _to_image_coords

    pts = _to_image_coords(points[None], size, width, margin)[0]
    centres = np.stack(np.meshgrid(np.arange(size) + 0.5, np.arange(size) + 0.5), -1).reshape(-1, 2)
    a, b = pts[:-1], pts[1:]
    ab = b - a
    t = np.clip(((centres[:, None] - a) * ab).sum(-1) / np.maximum((ab**2).sum(-1), 1e-12), 0, 1)
    d = np.linalg.norm(centres[:, None] - (a + t[..., None] * ab), axis=-1).min(1)
    return np.clip(width / 2 + 0.5 - d, 0, 1).reshape(size, size)


def test_fast_render_matches_exact_distance_render():
    rng = np.random.default_rng(2)
    trajs = np.stack([normalise(resample_arclength(letter_like(rng), 100)) for _ in range(8)])
    fast = render_batch(trajs)
    for traj, img in zip(trajs, fast):
        assert np.abs(img - _exact_render(traj)).max() < 0.02


def test_render_rejects_impossible_settings():
    with pytest.raises(UsageError, match="room to draw"):
        render(np.array([[0.0, 0], [1, 1]]), size=8, stroke_width=4, margin=2)
