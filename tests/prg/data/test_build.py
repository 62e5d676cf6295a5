"""Tests of ``prg.data.build`` (moved from the suite on: the dataset build as a function: contents,
writer-disjointness, reproducibility)."""

import json

import numpy as np
import pytest

from prg.data.build import build_dataset, read_data_settings
from prg.data.preprocess import PreprocessSettings
from prg.data.store import load_split
from prg.errors import UsageError
from tests.conftest import small_data_cfg


def test_two_builds_with_the_same_seed_are_byte_identical(tmp_path):
    cfg = small_data_cfg(
        **{
            "data.synthetic.n_writers": 4,
            "data.splits.train": 0.5,
            "data.splits.val": 0.25,
            "data.splits.test": 0.25,
        }
    )
    a = build_dataset(cfg, tmp_path / "a", workers=1, progress=False, figures=False).out_dir
    b = build_dataset(cfg, tmp_path / "b", workers=2, progress=False, figures=False).out_dir
    for name in ("train.npz", "val.npz", "test.npz", "manifest.json"):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name


def test_rebuild_replaces_the_old_dataset_and_leaves_no_temporaries(tmp_path):
    cfg = small_data_cfg(**{"data.augment.enabled": False})
    build_dataset(cfg, tmp_path, workers=1, progress=False, figures=True)
    result = build_dataset(cfg, tmp_path, workers=1, progress=False, figures=True)
    assert sorted(p.name for p in (tmp_path / "prepared").iterdir()) == ["synthetic"]
    figures = sorted(p.name for p in (result.out_dir / "figures").iterdir())
    assert figures == ["images_per_class.png", "samples_per_class.png"]


def test_failed_build_leaves_nothing(tmp_path):
    cfg = small_data_cfg(**{"data.image.stroke_width": 30.0})
    with pytest.raises(UsageError, match="stroke_width"):
        build_dataset(cfg, tmp_path, workers=1, progress=False)
    assert not (tmp_path / "prepared").exists() or not any((tmp_path / "prepared").iterdir())


@pytest.mark.parametrize(
    "override, match",
    [
        ({"data.augment.per_class": -5}, "per_class"),
        ({"data.preprocess.n_points": 1}, "n_points"),
        ({"data.source": "mnist"}, "unknown data source"),
        ({"data.image.size": "big"}, "data.image.size"),
        ({"data.name": "../escape"}, "plain folder name"),
    ],
)
def test_nonsense_numbers_are_named(tmp_path, override, match):
    with pytest.raises(UsageError, match=match):
        build_dataset(small_data_cfg(**override), tmp_path, workers=1, progress=False)


@pytest.mark.parametrize(
    "override, message",
    [
        ({"data.seed": -1}, "data.seed must be an integer >= 0, got -1"),
        (
            {"data.preprocess.n_points": 1},
            "data.preprocess.n_points must be an integer >= 2, got 1",
        ),
        (
            {"data.image.margin": -0.5},
            "data.image.margin must be a finite number >= 0.0, got -0.5",
        ),
        (
            {"data.image.stroke_width": 30.0},
            "data.image: 2*margin + stroke_width must be < size (28)",
        ),
        (
            {"data.augment.max_components": 0},
            "data.augment.max_components must be an integer >= 1, got 0",
        ),
        (
            {"data.synthetic.n_writers": 0},
            "data.synthetic.n_writers must be an integer >= 1, got 0",
        ),
        (
            {"data.synthetic.slant": "[0.5,0.1]"},
            "data.synthetic.slant range [0.5, 0.1] has min > max",
        ),
        (
            {"data.synthetic.width": "[0.0,1.0]"},
            "data.synthetic: width and size must be > 0, roundness/jitter >= 0",
        ),
        (
            {"data.name": "../escape"},
            "data.name '../escape' is a path, not a plain folder name: accepted are printable "
            "characters without '/', not starting with '.', at most 255 bytes",
        ),
    ],
)
def test_a_refused_setting_is_named_by_its_config_path(override, message):
    with pytest.raises(UsageError) as caught:
        read_data_settings(small_data_cfg(**override))
    assert str(caught.value) == message


def test_read_settings_are_typed_and_match_the_config():
    settings = read_data_settings(small_data_cfg(**{"data.augment.snr_target_db": 20}))
    assert settings.name == "synthetic" and settings.synthetic.n_writers == 5
    assert settings.preprocess == PreprocessSettings(100, 1.0)
    assert settings.augment.per_class == 3 and type(settings.augment.snr_target_db) is float
    assert settings.uji is None


@pytest.mark.parametrize(
    ("seed", "n_writers", "fractions"),
    [(1, 6, (0.5, 0.25, 0.25)), (2, 6, (0.7, 0.15, 0.15)), (3, 5, (0.4, 0.2, 0.4))],
)
def test_augmented_samples_keep_their_parents_writer_and_split_for_several_seeds(
    tmp_path, seed, n_writers, fractions
):
    """Writer-disjointness must hold through augmentation whatever the split assignment is: one
    fixture seed can put the writers in an order where a sample pointed at the wrong row still
    gets a training writer. A few small builds (6 characters) with other seeds and fractions."""
    train_f, val_f, test_f = fractions
    cfg = small_data_cfg(
        **{
            "data.synthetic.n_writers": n_writers,
            "data.augment.per_class": 3,
            "data.seed": seed,
            "data.splits.train": train_f,
            "data.splits.val": val_f,
            "data.splits.test": test_f,
        }
    )
    cfg["synthetic"]["characters"] = "aeosT7"
    out = build_dataset(cfg, tmp_path, workers=1, progress=False, figures=False).out_dir
    splits = {s: load_split(out / f"{s}.npz") for s in ("train", "val", "test")}
    assignment = json.loads((out / "manifest.json").read_text())["splits"]
    assert set().union(*assignment.values()) == {f"SYN_W{w + 1:02d}" for w in range(n_writers)}
    for split, arrays in splits.items():
        # every sample, augmented or not, belongs to a writer of its own split
        assert set(arrays["writer"]) <= set(assignment[split]), split
    for split in ("val", "test"):
        assert not splits[split]["augmented"].any()
        assert (splits[split]["parent"] == -1).all()
    train = splits["train"]
    children = np.flatnonzero(train["augmented"])
    assert len(children) == 3 * 6  # per_class x characters
    parents = train["parent"][children]
    assert ((parents >= 0) & (parents < len(train["label"]))).all()
    assert (~train["augmented"][parents]).all()
    assert (train["parent"][~train["augmented"]] == -1).all()
    np.testing.assert_array_equal(train["writer"][children], train["writer"][parents])
    np.testing.assert_array_equal(train["label"][children], train["label"][parents])
