"""Tests of ``prg.data.datamodule`` (moved from the suite on: the modality registry
(prg.models.modalities): one record per modality, and every part that handles modalities reads
it: the DataModule's batches, the test data, the classifiers' inputs, the networks, the
likelihoods and the shape check of a prepared dataset)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from prg.data.datamodule import PRGDataModule, check_model_shapes
from prg.errors import UsageError


def test_batches_are_dicts_keyed_by_modality(small_dataset):
    dm = PRGDataModule(small_dataset, "synthetic", batch_size=16)
    dm.setup("fit")
    batch = next(iter(dm.train_dataloader()))
    assert set(batch) == {"traj", "image", "label"}
    assert batch["traj"].shape == (16, 200) and batch["traj"].dtype == torch.float32
    assert batch["image"].shape == (16, 1, 28, 28) and batch["image"].dtype == torch.float32
    assert batch["image"].min() >= 0 and batch["image"].max() <= 1
    assert batch["label"].shape == (16,) and batch["label"].dtype == torch.long


def test_modalities_can_be_left_out(small_dataset):
    dm = PRGDataModule(small_dataset, "synthetic", modalities=["traj", "label"], batch_size=8)
    batch = next(iter(dm.val_dataloader()))
    assert set(batch) == {"traj", "label"}


def test_loader_covers_the_split_once_per_epoch(small_dataset):
    dm = PRGDataModule(small_dataset, "synthetic", batch_size=50)
    dm.setup("test")
    seen = sum(len(b["label"]) for b in dm.test_dataloader())
    assert seen == len(dm.datasets["test"])


def test_shuffle_is_seeded(small_dataset):
    first = [
        next(iter(PRGDataModule(small_dataset, "synthetic", seed=s).train_dataloader()))
        for s in (1, 1, 2)
    ]
    assert torch.equal(first[0]["label"], first[1]["label"])
    assert not torch.equal(first[0]["label"], first[2]["label"])


def test_bad_modalities_and_missing_dataset(tmp_path, small_dataset):
    with pytest.raises(UsageError, match="modalities"):
        PRGDataModule(small_dataset, "synthetic", modalities=["audio"])
    with pytest.raises(UsageError, match="prg-prepare"):
        PRGDataModule(tmp_path, "nothing").setup("fit")


def test_a_dataset_of_other_shapes_is_refused_naming_the_prepare_options():
    arrays = {
        "traj": np.zeros((4, 120), np.float32),
        "image": np.zeros((4, 32, 32), np.uint8),
        "label": np.zeros(4, np.int64),
    }
    with pytest.raises(UsageError) as err:
        check_model_shapes(arrays, "data/prepared/x")
    assert str(err.value) == (
        "dataset data/prepared/x was prepared with data.preprocess.n_points=60 and "
        "data.image.size=32, but the models take data.preprocess.n_points=100 and "
        "data.image.size=28: rebuild it with `prg-prepare data.preprocess.n_points=100 "
        "data.image.size=28`"
    )
    arrays["traj"], arrays["image"] = np.zeros(4, np.float32), np.zeros((4, 28, 30), np.uint8)
    with pytest.raises(UsageError, match=r"n_points=\(4,\) and data.image.size=\(28, 30\)"):
        check_model_shapes(arrays, "x")
    check_model_shapes({"label": arrays["label"]}, "x")  # labels have no shape option


def _orders(loader, epochs, batches=None):
    out = []
    for _ in range(epochs):
        out.append([b.tolist() for _, b in zip(range(batches or 10**9), loader)])
    return out


def test_the_training_order_is_torchs_random_sampler_epoch_after_epoch():
    from torch.utils.data import DataLoader

    from prg.data.datamodule import ResumableSampler

    data = list(range(300))
    plain = DataLoader(
        data, batch_size=32, shuffle=True, generator=torch.Generator().manual_seed(4)
    )
    sampler = ResumableSampler(data, torch.Generator().manual_seed(4))
    ours = DataLoader(data, batch_size=32, sampler=sampler, generator=sampler.generator)
    assert _orders(ours, 3) == _orders(plain, 3)  # whole epochs
    plain = DataLoader(
        data, batch_size=32, shuffle=True, generator=torch.Generator().manual_seed(4)
    )
    sampler = ResumableSampler(data, torch.Generator().manual_seed(4))
    ours = DataLoader(data, batch_size=32, sampler=sampler, generator=sampler.generator)
    assert _orders(ours, 3, 4) == _orders(plain, 3, 4)  # epochs cut short (limit_train_batches)


def test_a_resumed_order_goes_on_where_it_stopped():
    from torch.utils.data import DataLoader

    from prg.data.datamodule import ResumableSampler

    data = list(range(300))
    sampler = ResumableSampler(data, torch.Generator().manual_seed(9))
    loader = DataLoader(data, batch_size=32, sampler=sampler, generator=sampler.generator)
    first = _orders(loader, 1)[0]
    it = iter(loader)
    second_start = [next(it).tolist() for _ in range(3)]  # 3 batches of epoch 2, then a stop
    epoch_state, now = sampler.epoch_state, sampler.generator.get_state()
    rest_of_second = [b.tolist() for b in it]
    third = _orders(loader, 1)[0]

    again = ResumableSampler(data, torch.Generator().manual_seed(123))  # another process
    again.generator.set_state(now)
    again.resume(epoch_state, 3 * 32)
    loader = DataLoader(data, batch_size=32, sampler=again, generator=again.generator)
    assert _orders(loader, 2) == [rest_of_second, third]
    assert first != second_start + rest_of_second  # a new order each epoch
