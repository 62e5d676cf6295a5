"""phi_T and phi_I (prg.pipeline.perceive) against the prepared dataset's own trajectories/images."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from PIL import Image, ImageDraw

from prg.data.preprocess import (
    preprocess_stroke,
    resample_arclength,
)
from prg.data.store import load_split
from prg.errors import UsageError
from prg.pipeline.perceive import (
    load_image,
    perceive_letter_images,
    perceive_trajectories,
    segment_word_image,
)
from tests.helpers.properties import examples, polylines

PAPER, INK = (245, 240, 230), (20, 30, 60)


DARK_PAPER, LIGHT_INK = (10, 10, 20), (230, 230, 200)


@pytest.fixture(scope="module")
def test_split(small_dataset):
    data = load_split(small_dataset / "prepared" / "synthetic" / "test.npz")
    rng = np.random.default_rng(0)
    idx = rng.choice(len(data["traj"]), size=min(12, len(data["traj"])), replace=False)
    return data["traj"][idx].reshape(len(idx), -1, 2), data["image"][idx] / 255.0


def draw_letter(pts, width=200, height=300, pen=12, dark_on_light=True):
    """Draw a y-up trajectory as an RGB image with a round pen (Pillow), letter 70 % of the side."""
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre = (lo + hi) / 2
    scale = 0.7 * min(width, height) / (hi - lo).max()
    xy = [
        (width / 2 + (x - centre[0]) * scale, height / 2 - (y - centre[1]) * scale) for x, y in pts
    ]
    paper, ink = (PAPER, INK) if dark_on_light else (DARK_PAPER, LIGHT_INK)
    img = Image.new("RGB", (width, height), paper)
    draw = ImageDraw.Draw(img)
    draw.line(xy, fill=ink, width=pen, joint="curve")
    for x, y in (xy[0], xy[-1]):  # round caps
        draw.ellipse([x - pen / 2, y - pen / 2, x + pen / 2, y + pen / 2], fill=ink)
    return np.asarray(img)


def correlations(a, b):
    return np.array([np.corrcoef(x.ravel(), y.ravel())[0, 1] for x, y in zip(a, b, strict=True)])


# ---------------------------------------------------------------------------------------------
# phi_T
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [37, 100, 250])
def test_trajectories_match_dataset_after_scale_shift_resample(test_split, n):
    trajs, _ = test_split
    # tablet coordinates: y down, scaled, shifted, another number of points
    raw = [resample_arclength(p, n) * [137.0, -137.0] + [500.0, 300.0] for p in trajs]
    out = perceive_trajectories(raw, y_down=True)
    assert out.shape == (len(trajs), 200) and out.dtype == np.float32
    diff = np.abs(out - trajs.reshape(len(trajs), -1))
    # measured (12 test samples): mean 0.007-0.014, max 0.09-0.14 (re-smoothing at sharp corners)
    assert diff.mean() < 0.03
    assert diff.max() < 0.3


def test_trajectories_y_up_and_invariance(test_split):
    trajs, _ = test_split
    p = trajs[0]
    a = perceive_trajectories([p])
    b = perceive_trajectories([p * 0.01 - 7.0])
    c = perceive_trajectories([p * [1.0, -1.0]], y_down=True)
    np.testing.assert_allclose(a, b, atol=1e-4)  # float32 output
    np.testing.assert_allclose(a, c, atol=1e-6)
    pts = a.reshape(-1, 2)
    np.testing.assert_allclose(pts.mean(axis=0), 0.0, atol=1e-5)
    assert np.isclose(np.abs(pts).max(), 1.0)


@pytest.mark.parametrize(
    ("bad", "match"),
    [
        (np.array([[0.0, 0.0], [np.nan, 1.0]]), "letter 1: .*NaN"),
        (np.array([[0.0, 0.0]]), "letter 1: .*at least 2 points"),
        (np.ones((5, 2)), "letter 1: .*zero length"),
        (np.ones((5, 3)), r"letter 1: .*shape \(n, 2\)"),
    ],
)
def test_trajectories_bad_input(bad, match):
    good = np.array([[0.0, 0.0], [1.0, 2.0], [2.0, 0.0]])
    with pytest.raises(UsageError, match=match):
        perceive_trajectories([good, bad])


def test_trajectories_empty():
    with pytest.raises(UsageError, match="empty"):
        perceive_trajectories([])


# ---------------------------------------------------------------------------------------------
# phi_I
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("dark_on_light", [True, False])
@pytest.mark.parametrize("pen", [5, 12, 24])
def test_letter_images_match_dataset_images(test_split, dark_on_light, pen):
    trajs, images = test_split
    drawn = [draw_letter(p, pen=pen, dark_on_light=dark_on_light) for p in trajs]
    out = perceive_letter_images(drawn)
    assert out.shape == (len(trajs), 1, 28, 28) and out.dtype == np.float32
    assert out.min() >= 0.0 and out.max() <= 1.0
    corr = correlations(out[:, 0], images)
    mad = np.abs(out[:, 0] - images).mean(axis=(1, 2))
    # measured on 40 samples of the full test split: corr mean 0.91-0.98, min 0.81 (pen 25);
    # mean abs diff 0.02-0.05 per image, max 0.09 (0.14 on one fixture sample with pen 24)
    assert corr.mean() > 0.85 and corr.min() > 0.7
    assert mad.mean() < 0.07 and mad.max() < 0.2


def test_letter_images_formats_agree(test_split):
    trajs, _ = test_split
    rgb = draw_letter(trajs[0])
    grey = rgb.mean(axis=2)
    rgba = np.concatenate([rgb, np.full((*rgb.shape[:2], 1), 255, np.uint8)], axis=2)
    ref = perceive_letter_images([rgb])
    for other in (rgb / 255.0, grey.astype(np.uint8), grey / 255.0, rgba):
        np.testing.assert_allclose(perceive_letter_images([other]), ref, atol=0.03)


def test_faint_noise_does_not_move_the_crop(test_split):
    trajs, images = test_split
    img = draw_letter(trajs[0]).astype(np.float64)
    rng = np.random.default_rng(1)
    noisy = np.clip(img - rng.uniform(0, 12, img.shape[:2])[..., None], 0, 255).astype(np.uint8)
    noisy[5, 5] = INK  # one speck far from the letter
    clean = perceive_letter_images([img.astype(np.uint8)])
    out = perceive_letter_images([noisy])
    assert correlations(out[:, 0], clean[:, 0])[0] > 0.97
    assert correlations(out[:, 0], images[:1])[0] > 0.85


def test_blank_and_bad_images():
    letter = np.full((30, 30), 255, np.uint8)
    letter[10:20, 14:16] = 0
    with pytest.raises(UsageError, match=r"letter 1: .*blank"):
        perceive_letter_images([letter, np.full((40, 40, 3), 200, np.uint8)])
    with pytest.raises(UsageError, match=r"letter 0: .*must be"):
        perceive_letter_images([np.zeros((5, 5, 2))])
    with pytest.raises(UsageError, match=r"letter 0: .*NaN"):
        perceive_letter_images([np.full((5, 5), np.nan)])
    with pytest.raises(UsageError, match="empty"):
        perceive_letter_images([])


# ---------------------------------------------------------------------------------------------
# segmentation and files
# ---------------------------------------------------------------------------------------------


def test_segment_word_image(test_split):
    trajs, images = test_split
    letters = [draw_letter(p, width=160, height=220, pen=10) for p in trajs[:4]]
    gap = np.full((220, 25, 3), PAPER, np.uint8)
    word = np.concatenate([letters[0], gap, letters[1], gap, letters[2], gap, letters[3]], axis=1)
    parts = segment_word_image(word)
    assert len(parts) == 4
    out = perceive_letter_images(parts)
    alone = perceive_letter_images(letters)
    np.testing.assert_allclose(out, alone, atol=1e-6)
    corr = correlations(out[:, 0], images[:4])
    assert corr.min() > 0.8
    # each part is its own letter, in order: best match on the diagonal
    cross = np.array([correlations(out[:, 0], np.roll(images[:4], k, axis=0)) for k in range(4)])
    assert np.all(cross[0] >= cross[1:].max(axis=0) - 1e-9) or corr.min() > 0.9


def test_segment_merges_horizontally_overlapping_parts():
    word = np.full((60, 80), 255, np.uint8)
    word[25:55, 10:14] = 0  # stem of an "i"
    word[12:17, 10:14] = 0  # its dot, separate but above it
    word[20:55, 40:44] = 0
    word[20:24, 40:60] = 0  # an "r"-like second letter
    parts = segment_word_image(word)
    assert len(parts) == 2
    assert parts[0].shape[1] < parts[1].shape[1] + 40


def test_segment_blank():
    with pytest.raises(UsageError, match="blank"):
        segment_word_image(np.zeros((20, 20), np.uint8))


def test_load_image(tmp_path, test_split):
    trajs, _ = test_split
    rgb = draw_letter(trajs[0])
    Image.fromarray(rgb).save(tmp_path / "a.png")
    Image.fromarray(rgb[..., 0]).save(tmp_path / "g.png")
    np.testing.assert_array_equal(load_image(tmp_path / "a.png"), rgb)
    assert load_image(tmp_path / "g.png").shape == rgb.shape[:2]
    (tmp_path / "bad.png").write_text("not an image")
    with pytest.raises(UsageError, match=r"bad\.png: not an image"):
        load_image(tmp_path / "bad.png")
    with pytest.raises(UsageError, match=r"missing\.png: no such image file"):
        load_image(tmp_path / "missing.png")


@examples(30)
@given(strokes=st.lists(polylines(max_points=30, max_offset=100.0), min_size=1, max_size=4))
def test_perceiving_several_strokes_gives_one_normalised_row_each(strokes):
    out = perceive_trajectories(strokes, y_down=True)
    assert out.shape == (len(strokes), 200) and out.dtype == np.float32
    for stroke, row in zip(strokes, out):
        expected = preprocess_stroke(stroke, 100, 1.0, y_down=True)
        np.testing.assert_allclose(row.reshape(100, 2), expected, atol=1e-6)
