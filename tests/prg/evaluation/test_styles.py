"""Tests of ``prg.evaluation.styles`` (moved from the suite on: the likeness table of generation
modes and the style rates, on small known cases)."""

from __future__ import annotations

import numpy as np
import pytest

from prg.evaluation.styles import class_centred, style_rates, style_summary, writer_features
from tests.conftest import stand_in_hands
from tests.helpers.modes import setting  # noqa: F401 (fixtures)


def test_writer_features_ignore_position_and_see_slant():
    bank = stand_in_hands(n_writers=1)
    letters = bank.traj[:5].reshape(5, 100, 2)
    moved = (letters + np.array([0.3, -0.2])).reshape(5, -1)
    np.testing.assert_allclose(writer_features(moved), writer_features(bank.traj[:5]), atol=1e-9)
    sheared = (letters @ np.array([[1.0, 0.5], [0.0, 1.0]]).T).reshape(5, -1)
    slant = -2  # the principal axis angle
    assert not np.allclose(
        writer_features(sheared)[:, slant], writer_features(bank.traj[:5])[:, slant]
    )


def test_class_centring_subtracts_each_class_mean():
    features = np.array([[1.0, 2.0], [3.0, 4.0], [10.0, 0.0]])
    labels = np.array([0, 0, 1])
    means = {0: np.array([2.0, 3.0]), 1: np.array([10.0, 0.0])}
    np.testing.assert_array_equal(
        class_centred(features, labels, means), [[-1.0, -1.0], [1.0, 1.0], [0.0, 0.0]]
    )


def test_style_rates_report_each_seed_and_k_against_the_writers_own_letters(setting):
    model, bank, test = setting
    rows = style_rates(model, bank, test, ks=(1, 3), seeds=(0, 1), n_eval=6)
    assert [(r["seed"], r["k"]) for r in rows] == [(0, 1), (0, 3), (1, 1), (1, 3)]
    for r in rows:
        assert r["chance"] == 1 / 4 and r["writers"] == 4
        assert 0 <= r["generated"] <= 1 and 0 <= r["real"] <= 1
        assert r["letters"] == 4 * 6  # every writer wrote each set-aside class once
    summary = style_summary([{"family": "muse", **r} for r in rows])
    assert [s["k"] for s in summary] == [1, 3]
    first = summary[0]
    assert first["generated"] == pytest.approx(
        np.mean([rows[0]["generated"], rows[2]["generated"]])
    )
    assert first["ratio"] == pytest.approx(first["generated"] / first["real"])
