"""Tests of ``prg.models.modalities`` (moved from the suite on: the modality registry
(prg.models.modalities): one record per modality, and every part that handles modalities reads
it: the DataModule's batches, the test data, the classifiers' inputs, the networks, the
likelihoods and the shape check of a prepared dataset)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from prg.data.datamodule import ModalityDataset
from prg.data.store import load_split
from prg.evaluation import classifiers as clf
from prg.evaluation.run import load_test_data
from prg.models.likelihoods import Likelihoods
from prg.models.modalities import IMAGE, LABEL, LETTER, MODALITIES, NAMES, TRAJ, in_order, letters


def test_the_papers_three_modalities_in_its_order():
    assert NAMES == (TRAJ, LABEL, IMAGE) == ("traj", "label", "image")
    assert dict(LETTER) == {"traj": "T", "label": "S", "image": "I"}
    assert in_order({"image": 1, "traj": 2, "audio": 3}) == ("traj", "image")
    assert letters(("image", "label"), ",") == "S,I"
    with pytest.raises(TypeError):
        MODALITIES["audio"] = MODALITIES["traj"]  # read-only


# the models' inputs as the DataModule, the evaluation and the classifiers each wrote them before
# the registry held the conversion
AS_BEFORE = {
    "traj": lambda a: torch.from_numpy(a).float(),
    "label": lambda a: torch.from_numpy(a.astype(np.int64)),
    "image": lambda a: torch.from_numpy(a).float().div(255.0).unsqueeze(1),
}


@pytest.mark.parametrize("name", NAMES)
def test_a_stored_split_becomes_model_inputs_of_the_records_shape_and_dtype(name, small_dataset):
    spec = MODALITIES[name]
    arrays = load_split(small_dataset / "prepared/synthetic/val.npz")
    assert arrays[name].shape[1:] == spec.stored_shape
    assert arrays[name].dtype == spec.stored_dtype
    x = spec.to_tensor(arrays[name][:5])
    assert x.shape == (5, *spec.shape) and x.dtype == spec.dtype
    assert torch.equal(x, AS_BEFORE[name](arrays[name][:5]))
    # one conversion for the DataModule (a batch and a sample), the test data, the classifiers
    dataset = ModalityDataset(arrays, [name])
    assert torch.equal(dataset.__getitems__([0, 1, 2, 3, 4])[name], x)
    assert torch.equal(dataset[3][name], x[3])
    test = load_split(small_dataset / "prepared/synthetic/test.npz")[name]
    assert torch.equal(
        load_test_data(small_dataset / "prepared/synthetic")[name], spec.to_tensor(test)
    )
    if name in clf.MODALITIES:
        assert torch.equal(clf.to_input(name, arrays[name][:5]), x)


def test_images_are_held_as_ink_and_made_pixels_in_unit_range(small_dataset):
    arrays = load_split(small_dataset / "prepared/synthetic/val.npz")
    spec = MODALITIES[IMAGE]
    assert spec.load(arrays[IMAGE]).dtype == torch.uint8  # compact in memory
    pixels = spec.to_tensor(arrays[IMAGE][:4])
    np.testing.assert_allclose(pixels[:, 0].numpy() * 255, arrays[IMAGE][:4], atol=1e-4)


@pytest.mark.parametrize("name", NAMES)
def test_networks_and_likelihood_fit_the_records_shape(name):
    spec = MODALITIES[name]
    torch.manual_seed(0)
    if spec.dtype == torch.int64:
        x = torch.randint(0, 62, (3, *spec.shape))
    else:
        x = torch.rand(3, *spec.shape)
    mu, logvar = spec.encoder(16)(x)
    assert mu.shape == logvar.shape == (3, 16)
    params = spec.decoder(16)(mu)
    assert Likelihoods().log_prob(name, params, x).shape == (3,)
    assert Likelihoods.mean(name, params).shape[0] == 3
    decoded = Likelihoods.as_input(name, params)
    assert decoded.shape == x.shape and decoded.dtype == x.dtype  # imputation feeds it back
