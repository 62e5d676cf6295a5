"""Tests of ``prg.recording.views`` (moved from the suite on: rerun recordings: a written word with
its inputs and animated DMP rollout, read back from disk)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.helpers.recording import FLOAT32


def test_framing_bounds_hold_every_point_with_a_margin():
    from prg.recording import framing

    rng = np.random.default_rng(0)
    for scale in (0.01, 1.0, 30.0):
        pts = rng.normal(size=(50, 2)) * scale + rng.normal(size=2) * 10
        bounds = framing(pts, margin=0.1)
        (stored,) = bounds.range.as_arrow_array().to_pylist()
        (x0, x1), (y0, y1) = stored["x_range"], stored["y_range"]
        assert x0 < pts[:, 0].min() and x1 > pts[:, 0].max()
        assert y0 < pts[:, 1].min() and y1 > pts[:, 1].max()
        pad = 0.1 * max(np.ptp(pts, axis=0).max(), 1.0)
        assert np.isclose(x0, pts[:, 0].min() - pad) and np.isclose(y1, pts[:, 1].max() + pad)


def test_the_3d_eye_holds_every_point_and_is_no_farther_than_it_must_be():
    from prg.recording import framing_eye

    rng = np.random.default_rng(1)
    edge = np.tan(np.radians(55.0) / 2)  # Rerun's vertical field of view
    for aspect in (1.0, 1.6):
        for _ in range(5):
            pts = rng.normal(size=(40, 3)) * rng.uniform(0.01, 1.0, size=3) + rng.normal(size=3)
            looking_from = rng.normal(size=3) + np.array([0.0, 0.0, 2.0])
            eye = framing_eye(pts, looking_from, margin=0.1, aspect=aspect)
            (position,) = eye.position.as_arrow_array().to_pylist()
            (target,) = eye.look_target.as_arrow_array().to_pylist()
            forward = np.subtract(target, position)
            forward /= np.linalg.norm(forward)
            np.testing.assert_allclose(
                forward, -looking_from / np.linalg.norm(looking_from), atol=FLOAT32
            )
            right = np.cross(forward, [0.0, 0.0, 1.0])
            right /= np.linalg.norm(right)
            up = np.cross(right, forward)
            rel = pts - position
            depth = rel @ forward
            # the share of the picture (inside the margin) the farthest point out takes
            taken = max(
                (np.abs(rel @ right) / depth).max() / (edge * aspect / 1.1),
                (np.abs(rel @ up) / depth).max() / (edge / 1.1),
            )
            assert depth.min() > 0 and taken <= 1 + FLOAT32
            # tight: a point touches the margin, unless the eye keeps its least distance
            assert taken > 1 - FLOAT32 or depth.min() == pytest.approx(0.035, rel=FLOAT32)
