"""Lightning DataModule over a prepared dataset; batches are dicts keyed by modality."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import lightning as L
import numpy as np
import torch
from torch.utils.data import DataLoader, Dataset, RandomSampler

from prg.data.store import load_split
from prg.errors import UsageError
from prg.models.modalities import LABEL, MODALITIES, NAMES


class ModalityDataset(Dataset):
    """In-memory tensors of one split; indexing by a list of indices returns a whole batch.

    ``dataset[i]`` is a dict of single samples; ``dataset.__getitems__(indices)`` (used by the
    DataLoader) gathers a batch with one tensor index per modality instead of collating
    ``batch_size`` small dicts.

    Each modality is held as stored (images as uint8 ink) and made a model input per batch
    (:class:`prg.models.modalities.Modality`: ``load``, then ``prepare``).
    """

    def __init__(self, arrays: dict[str, np.ndarray], modalities: Sequence[str]):
        self.modalities = tuple(modalities)
        self.tensors = {m: MODALITIES[m].load(arrays[m]) for m in self.modalities}
        self.length = len(arrays[LABEL])  # every split holds the class of each sample

    def __len__(self) -> int:
        return self.length

    def _gather(self, index) -> dict[str, torch.Tensor]:
        return {m: MODALITIES[m].prepare(v[index]) for m, v in self.tensors.items()}

    def __getitem__(self, index: int) -> dict[str, torch.Tensor]:
        return self._gather(index)

    def __getitems__(self, indices: list[int]) -> dict[str, torch.Tensor]:
        return self._gather(torch.as_tensor(indices, dtype=torch.long))


def _identity(batch):
    return batch


def read_manifest(root: str | Path) -> dict[str, Any]:
    """The ``manifest.json`` of the prepared dataset folder ``root``, checked to be one."""
    path = Path(root) / "manifest.json"
    rebuild = f"rebuild the dataset with `prg-prepare data={Path(root).name}`"
    if not path.is_file():
        raise UsageError(f"no prepared dataset at {root}: run `prg-prepare` first")
    try:
        manifest = json.loads(path.read_bytes())
    except (OSError, ValueError) as err:  # UnicodeDecodeError and JSONDecodeError included
        raise UsageError(
            f"dataset manifest {path} is not readable JSON ({err}): {rebuild}"
        ) from None
    if not isinstance(manifest, dict) or not isinstance(manifest.get("source"), str):
        raise UsageError(
            f"dataset manifest {path} is not a prg-prepare manifest (a JSON object with a "
            f'"source" name): {rebuild}'
        )
    return manifest


def check_model_shapes(arrays: dict[str, np.ndarray], path: str | Path) -> None:
    """Refuse a split whose samples do not have the shapes the models take (each modality's
    ``stored_shape`` in :data:`prg.models.modalities.MODALITIES`: 100 trajectory points, 28 x 28
    images), naming the ``prg-prepare`` options that set them, as prepared and as needed."""
    wrong = []
    for spec in MODALITIES.values():
        array, option = arrays.get(spec.name), spec.shape_option
        if option is None or array is None or array.shape[1:] == spec.stored_shape:
            continue
        wrong.append((option.key, option.value(array.shape), option.value((0, *spec.stored_shape))))
    if wrong:
        has = " and ".join(f"{key}={got}" for key, got, _ in wrong)
        needs = " and ".join(f"{key}={want}" for key, _, want in wrong)
        fix = " ".join(f"{key}={want}" for key, _, want in wrong)
        raise UsageError(
            f"dataset {path} was prepared with {has}, but the models take {needs}: "
            f"rebuild it with `prg-prepare {fix}`"
        )


class ResumableSampler(RandomSampler):
    """The training shuffle, a :class:`torch.utils.data.RandomSampler` (the same orders, drawn
    from ``generator``) that a resumed training can put back where it stopped.

    ``epoch_state`` is the generator's state just before the current epoch's order was drawn;
    :meth:`resume` makes the next epoch draw from a saved one and leave out the samples already
    trained on, so a training resumed mid-epoch sees the rest of that epoch's batches in the
    uninterrupted run's order (:class:`prg.training.callbacks.LastCheckpoint`).
    """

    def __init__(self, data_source, generator: torch.Generator):
        super().__init__(data_source, generator=generator)
        self.epoch_state: torch.Tensor | None = None
        self._resume: tuple[torch.Tensor, int] | None = None

    def resume(self, epoch_state: torch.Tensor, samples_done: int) -> None:
        """Draw the next order from ``epoch_state`` and skip its first ``samples_done``."""
        self._resume = (epoch_state, samples_done)

    def __iter__(self):
        skip = 0
        if self._resume is not None:
            state, skip = self._resume
            self.generator.set_state(state)
            self._resume = None
        self.epoch_state = self.generator.get_state()
        for i, index in enumerate(super().__iter__()):
            if i >= skip:
                yield index


class PRGDataModule(L.LightningDataModule):
    """Train/val/test loaders over ``<data_dir>/prepared/<name>/``.

    Parameters
    ----------
    data_dir : path
        Root data folder (``paths.data_dir``).
    name : str
        Prepared dataset name (``data.name``).
    modalities : sequence of str
        Any non-empty subset of :data:`prg.models.modalities.NAMES` (``traj``, ``label``, ``image``);
        batches hold only these keys, each a model input of its modality's ``shape`` and
        ``dtype``: ``traj`` float (B, 200), ``label`` long (B,), ``image`` float (B, 1, 28, 28)
        in [0, 1].
    batch_size, num_workers, pin_memory : loader settings
    seed : int
        Seeds the training shuffle.
    """

    def __init__(
        self,
        data_dir: str | Path,
        name: str,
        modalities: Sequence[str] = NAMES,
        batch_size: int = 128,
        eval_batch_size: int | None = None,
        num_workers: int = 0,
        pin_memory: bool = False,
        seed: int = 0,
    ):
        super().__init__()
        modalities = tuple(modalities)
        unknown = [m for m in modalities if m not in MODALITIES]
        if unknown or not modalities:
            raise UsageError(
                f"modalities {list(modalities)} not accepted: choose a non-empty subset of "
                f"{list(NAMES)}"
            )
        if batch_size < 1 or num_workers < 0:
            raise UsageError(
                f"batch_size must be >= 1 and num_workers >= 0, got {batch_size}, {num_workers}"
            )
        self.root = Path(data_dir) / "prepared" / name
        self.modalities = modalities
        self.batch_size = batch_size
        self.eval_batch_size = eval_batch_size or batch_size
        self.num_workers = num_workers
        self.pin_memory = pin_memory
        self.seed = seed
        self.datasets: dict[str, ModalityDataset] = {}
        self.train_letters: dict[str, np.ndarray] | None = None
        self.train_sampler: ResumableSampler | None = None  # the training loader's, once made
        # set by a resumed training before its loader is made (prg.training.callbacks)
        self.resume_order: dict[str, Any] | None = None

    @property
    def manifest(self) -> dict[str, Any]:
        return read_manifest(self.root)

    def setup(self, stage: str | None = None) -> None:
        wanted = {"fit": ("train", "val"), "validate": ("val",), "test": ("test",)}.get(
            stage or "", ("train", "val", "test")
        )
        for split in wanted:
            if split not in self.datasets:
                path = self.root / f"{split}.npz"
                arrays = load_split(path)
                check_model_shapes(arrays, self.root)
                if len(arrays[LABEL]) == 0:
                    raise UsageError(
                        f"dataset split {path} is empty: the {split} split needs writers "
                        f"(data.splits.{split} > 0 when the dataset is prepared)"
                    )
                self.datasets[split] = ModalityDataset(arrays, self.modalities)
                if split == "train":  # the writers' letters a checkpoint keeps (prg.pipeline.hands)
                    self.train_letters = {
                        k: arrays[k] for k in ("traj", "label", "writer", "augmented")
                    }

    def _loader(self, split: str, shuffle: bool) -> DataLoader:
        if split not in self.datasets:
            self.setup(None)
        dataset = self.datasets[split]
        sampler = None
        if shuffle:  # one generator per training: each epoch's order follows from the seed
            generator = torch.Generator().manual_seed(self.seed)
            sampler = self.train_sampler = ResumableSampler(dataset, generator)
            if self.resume_order is not None:  # a resumed training: where its order stopped
                generator.set_state(self.resume_order["generator"])
                if self.resume_order["samples_done"]:
                    sampler.resume(self.resume_order["epoch"], self.resume_order["samples_done"])
        return DataLoader(
            dataset,
            batch_size=self.batch_size if split == "train" else self.eval_batch_size,
            sampler=sampler,
            num_workers=self.num_workers,
            pin_memory=self.pin_memory,
            collate_fn=_identity,
            generator=sampler.generator if sampler else None,
            persistent_workers=self.num_workers > 0,
        )

    def train_dataloader(self) -> DataLoader:
        return self._loader("train", shuffle=True)

    def val_dataloader(self) -> DataLoader:
        return self._loader("val", shuffle=False)

    def test_dataloader(self) -> DataLoader:
        return self._loader("test", shuffle=False)
