"""Tests of ``prg.evaluation.handwriting``: the metric-key names of the likeness modes, and the
parts that are left out, with one warning naming what is missing, when the test split or the
checkpoints cannot support them."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest

from prg.data.store import save_split
from prg.evaluation.handwriting import kinematics_part, likeness_key, likeness_part, styles_part
from prg.evaluation.run import LoadedModel
from prg.evaluation.settings import EvaluationSettings


@pytest.mark.parametrize(
    ("mode", "key"),
    [
        ("hand (default)", "hand"),
        ("posterior (paper)", "posterior"),
        ("sampled T=0.5", "sampled_t0.5"),
        ("val writers", "val_writers"),
        ("train originals", "train_originals"),
    ],
)
def test_a_likeness_mode_becomes_a_metric_key_part(mode, key):
    assert likeness_key(mode) == key


def _split(folder: Path, labels: list[int], writers: list[str]) -> Path:
    n = len(labels)
    save_split(
        folder / "test.npz",
        {
            "traj": np.zeros((n, 200), dtype=np.float32),
            "image": np.zeros((n, 28, 28), dtype=np.float32),
            "label": np.asarray(labels),
            "writer": np.asarray(writers),
            "augmented": np.zeros(n, dtype=bool),
            "parent": np.arange(n),
        },
    )
    return folder


def test_likeness_needs_four_letters_of_a_class(tmp_path, caplog):
    """The k-NN measures compare a letter with its 3 nearest: with 3 letters a class at most
    there is nothing to measure, and the warning says to prepare more writers."""
    data = _split(tmp_path, [0, 0, 0, 1, 1, 2], ["a", "b", "c", "a", "b", "c"])
    with caplog.at_level(logging.WARNING, logger="prg.evaluation.handwriting"):
        rows = likeness_part({}, data, None, EvaluationSettings())
    assert rows == []
    assert "at most 3 letters of a class" in caplog.text and "more writers" in caplog.text


def test_styles_need_two_writers_and_hands(tmp_path, caplog):
    one_writer = _split(tmp_path, [0, 1, 2, 3], ["w1"] * 4)
    with caplog.at_level(logging.WARNING, logger="prg.evaluation.handwriting"):
        assert styles_part({}, one_writer, EvaluationSettings()) == []
    assert "1 writer" in caplog.text
    caplog.clear()
    two_writers = _split(tmp_path, [0, 1, 0, 1], ["w1", "w1", "w2", "w2"])
    no_hands = {"muse": LoadedModel(model=None, info={}, path=tmp_path / "model.ckpt")}
    with caplog.at_level(logging.WARNING, logger="prg.evaluation.handwriting"):
        assert styles_part(no_hands, two_writers, EvaluationSettings()) == []
    assert "muse" in caplog.text and "no hands" in caplog.text


def test_kinematics_need_the_configured_family_with_hands(tmp_path, caplog):
    settings = EvaluationSettings()
    no_hands = {settings.kinematics.family: LoadedModel(None, {}, tmp_path / "model.ckpt")}
    for models in ({}, no_hands):
        caplog.clear()
        with caplog.at_level(logging.WARNING, logger="prg.evaluation.handwriting"):
            assert kinematics_part(models, settings) == []
        assert f"no {settings.kinematics.family} checkpoint with hands" in caplog.text
