"""The scripts beside the notes (docs/notes/*.py) run on a prepared dataset and refuse bad input
in one line."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest
import torch

from prg.data.hands import HandBank
from prg.data.store import load_split
from prg.data.synthetic import FONTS
from tests.conftest import small_data_cfg

SCRIPT = Path(__file__).resolve().parents[2] / "docs" / "notes" / "likeness_by_font.py"


@pytest.fixture(scope="module")
def script():
    spec = importlib.util.spec_from_file_location("likeness_by_font", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def prepared(tmp_path_factory) -> Path:
    """A synthetic dataset with three test writers: more test letters per class than the k-NN
    measures' k (the session's small dataset has one test writer)."""
    from prg.data.build import build_dataset

    root = tmp_path_factory.mktemp("data")
    cfg = small_data_cfg(**{"data.synthetic.n_writers": 20, "data.augment.per_class": 1})
    build_dataset(cfg, root, workers=1, progress=False, figures=False)
    return root / "prepared" / "synthetic"


@pytest.fixture(scope="module")
def inputs(prepared, untrained_muse_checkpoint, tmp_path_factory):
    """An untrained trajectory classifier, and the untrained MUSE with the training writers of
    the dataset as its hands (plumbing: the numbers mean nothing)."""
    from prg.evaluation.classifiers import TrajectoryClassifier, save_classifier

    folder = tmp_path_factory.mktemp("notes")
    torch.manual_seed(0)
    classifier = save_classifier(folder / "traj.pt", TrajectoryClassifier(), "traj", {})
    ckpt = torch.load(untrained_muse_checkpoint, weights_only=False)
    ckpt["hands"] = HandBank.from_split(load_split(prepared / "train.npz")).to_checkpoint()
    torch.save(ckpt, folder / "muse.ckpt")
    return classifier, folder / "muse.ckpt"


def test_fonts_are_the_generators_assigned_in_turn(script, prepared):
    fonts = script.writer_fonts(prepared)
    writers = {
        str(w)
        for split in ("train", "val", "test")
        for w in load_split(prepared / f"{split}.npz")["writer"]
    }
    assert writers <= set(fonts)
    for name, font in fonts.items():
        assert font == FONTS[(int(name.removeprefix("SYN_W")) - 1) % len(FONTS)]


def test_every_split_and_font_is_scored_and_written_as_json(
    script, prepared, inputs, tmp_path, capsys
):
    classifier, ckpt = inputs
    out = tmp_path / "rows.json"
    argv = ["--data", str(prepared), "--classifier", str(classifier), "--ckpt", str(ckpt)]
    assert script.main([*argv, "--draws", "1", "--out", str(out)]) == 0
    rows = json.loads(out.read_text())
    printed = capsys.readouterr().out.splitlines()
    assert len(printed) == 2 + len(rows)  # the header, then one line a row
    test_writers = {r["font"]: r["n_writers"] for r in rows if r["writers"] == "test"}
    assert test_writers["all"] == sum(n for f, n in test_writers.items() if f != "all") >= 1
    scored = [r for r in rows if "precision" in r]
    assert {r["letters"] for r in scored} == {"real", "muse hand"}
    for r in scored:
        assert 0 <= r["precision"] <= 1 and 0 <= r["recall"] <= 1 and 0 <= r["legible"] <= 1
    hands = [r for r in scored if r["letters"] == "muse hand"]
    bank = HandBank.from_split(load_split(prepared / "train.npz"))
    assert next(r for r in hands if r["font"] == "all")["n_writers"] == len(bank.writers)
    assert np.isfinite([r["c2st"] for r in scored]).all()


@pytest.mark.parametrize(
    "args, message",
    [
        (["--draws", "0"], "--draws must be at least 1, got 0"),
        (["--data", "{tmp}/none"], "none/test.npz: no such file"),
        (["--ckpt", "{tmp}/none.ckpt"], "none.ckpt: no such file"),
        (["--frobnicate"], "unrecognized arguments: --frobnicate"),
        (
            ["--data", "{small}"],
            "test.npz: a class has 2 test letters; the k-NN measures need more",
        ),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    script, prepared, small_dataset, inputs, tmp_path, capsys, args, message
):
    classifier, _ = inputs
    argv = ["--data", str(prepared), "--classifier", str(classifier)]
    assert (
        script.main(
            [
                *argv,
                *(
                    a.format(tmp=tmp_path, small=small_dataset / "prepared" / "synthetic")
                    for a in args
                ),
            ]
        )
        == 2
    )
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("likeness_by_font.py: error: ") and message in err[0]
