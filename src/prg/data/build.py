"""Build a prepared dataset: read a source, preprocess, split by writer, augment, render, write.

:func:`build_dataset` is the pure task behind ``prg-prepare``. It writes everything into a
temporary folder beside the target and renames it into place at the end, so an interrupted or
failed build leaves the previous dataset (or nothing) — never a half-written one.
"""

from __future__ import annotations

import contextlib
import logging
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from omegaconf import DictConfig, OmegaConf
from tqdm.auto import tqdm

import prg
from prg.alphabet import ALPHABET, char_to_label
from prg.checks import folder_name_problem
from prg.data.augment import AugmentSettings, augment
from prg.data.download import UJI_SHA256, UJI_URL, UjiSource, resolve_uji_path
from prg.data.preprocess import (
    TRAJ_LAYOUT,
    ImageSettings,
    PreprocessSettings,
    preprocess_stroke,
    render_batch,
)
from prg.data.samples import RawSample
from prg.data.splits import SPLITS, split_writers
from prg.data.store import save_split
from prg.data.synthetic import SyntheticSettings, generate
from prg.data.uji import read_uji, select_single_stroke_alphabet
from prg.errors import SettingsError, UsageError
from prg.fields import check_fields, checked, integer
from prg.files import atomic_path, json_text, sha256_file, staged_folder, write_json, write_text
from prg.resources import git_commit
from prg.signals import deferred

log = logging.getLogger(__name__)

SOURCES = ("synthetic", "uji")
PROVENANCE = "provenance.json"  # run facts of a build, beside manifest.json; not hashed by DVC
_RENDER_CHUNK = 2048  # trajectories per progress step of the render stage


@dataclass
class BuildResult:
    """What a build produced: the final folder, its manifest, and wall time per stage (s)."""

    out_dir: Path
    manifest: dict[str, Any]
    timings: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class DataSettings:
    """The ``data`` node of the config (``conf/data/*.yaml``), typed: :func:`read_data_settings`.

    Attributes
    ----------
    name : str
        Folder of the dataset under ``<data_dir>/prepared/``: a plain folder name.
    source : str
        ``synthetic`` or ``uji`` (:data:`SOURCES`), checked when the source is read.
    seed : int
        Seed of the splits, the augmentation and the figures, ``>= 0``.
    preprocess, image, augment
        The settings of those stages.
    splits : mapping
        Fractions of the writers per split, checked by :func:`~prg.data.splits.split_writers`.
    synthetic : SyntheticSettings or None
        The synthetic source's settings (source ``synthetic``).
    uji : UjiSource or None
        Where the UJI data comes from (source ``uji``).
    """

    name: str
    source: str
    seed: int = checked(0, integer, minimum=0)
    preprocess: PreprocessSettings = field(default_factory=PreprocessSettings)
    image: ImageSettings = field(default_factory=ImageSettings)
    augment: AugmentSettings = field(default_factory=AugmentSettings)
    splits: Mapping[str, Any] = field(default_factory=dict)
    synthetic: SyntheticSettings | None = None
    uji: UjiSource | None = None

    def __post_init__(self) -> None:
        problem = folder_name_problem(self.name)
        if problem:
            raise SettingsError(
                "name",
                f"{self.name!r} {problem}: accepted are printable characters without '/', not "
                "starting with '.', at most 255 bytes",
            )
        check_fields(self)


_SECTIONS = {"preprocess": PreprocessSettings, "image": ImageSettings, "augment": AugmentSettings}
_TUPLES = ("fonts", "slant", "width", "size", "rotation_deg", "roundness", "jitter")  # YAML lists


def _read(cls: type, values: Any, key: str, **extra: Any) -> Any:
    """``cls(**values, **extra)`` for the config node ``key``; a refused value is named by its
    path (``data.image.size``), a rule between fields or an unknown field under ``key``."""
    try:
        return cls(**(values or {}), **extra)
    except SettingsError as err:
        raise err.under(key) from None
    except (TypeError, UsageError) as err:
        raise UsageError(f"{key}: {err}") from None


def read_data_settings(data: Any) -> DataSettings:
    """The ``data`` node (plain containers, interpolations resolved) as :class:`DataSettings`.

    Raises
    ------
    UsageError
        Naming the config path of a refused value (``data.preprocess.n_points``).
    """
    if not isinstance(data, Mapping):
        raise UsageError("the data config must be a mapping (conf/data/*.yaml)")
    sections = {key: _read(cls, data.get(key), f"data.{key}") for key, cls in _SECTIONS.items()}
    if data.get("source") == "synthetic":
        syn = dict(data.get("synthetic") or {})
        syn.update({key: tuple(syn[key]) for key in _TUPLES if key in syn})
        syn.setdefault("seed", data.get("seed", 0))
        sections["synthetic"] = _read(SyntheticSettings, syn, "data.synthetic")
    elif data.get("source") == "uji":
        sections["uji"] = UjiSource(
            path=data.get("uji_path"),
            download=bool(data.get("download", False)),
            url=data.get("uji_url") or UJI_URL,
            sha256=data.get("uji_sha256") or UJI_SHA256,
        )
    scalars = {
        "name": str(data.get("name") or ""),
        "source": data.get("source"),
        "seed": data.get("seed", 0),
        "splits": data.get("splits") or {},
    }
    return _read(DataSettings, scalars, "data", **sections)


def load_raw_samples(
    settings: DataSettings, data_dir: Path, progress: bool
) -> tuple[list[RawSample], dict[str, Any]]:
    """Read the configured source; returns the raw samples and a description of the input."""
    if settings.source == "synthetic":
        synthetic = settings.synthetic or SyntheticSettings(seed=settings.seed)
        samples = generate(synthetic)
        return samples, {"kind": "synthetic", "sha256": synthetic.fingerprint(), "path": None}
    if settings.source == "uji":
        path = resolve_uji_path(settings.uji or UjiSource(), data_dir, progress=progress)
        samples = read_uji(path)
        return samples, {"kind": "uji", "sha256": sha256_file(path), "path": str(path)}
    raise UsageError(f"unknown data source {settings.source!r}: accepted are {list(SOURCES)}")


def preprocess_samples(
    samples: list[RawSample], n_points: int, smooth_sigma: float, progress: bool
) -> tuple[np.ndarray, list[RawSample], int]:
    """Preprocess every sample's stroke; drop (and count) degenerate ones (e.g. a single dot)."""
    trajs, kept, dropped = [], [], 0
    for s in tqdm(samples, desc="preprocess", unit="sample", disable=not progress, leave=False):
        try:
            trajs.append(preprocess_stroke(s.strokes[0], n_points, smooth_sigma, y_down=True))
            kept.append(s)
        except UsageError:
            dropped += 1
    shape = (0, n_points, 2)
    return (np.stack(trajs) if trajs else np.zeros(shape)), kept, dropped


def build_dataset(
    data_cfg: Any,
    data_dir: str | os.PathLike,
    *,
    workers: int = 2,
    progress: bool = True,
    figures: bool = True,
    metrics_path: str | os.PathLike | None = None,
) -> BuildResult:
    """Build ``<data_dir>/prepared/<name>/`` from the data config (``conf/data/*.yaml``).

    All or nothing: the dataset folder and ``metrics_path`` are written completely under
    temporary names first and only then renamed into place, so a failure (a full disk, a signal)
    leaves the previous dataset and metrics as they were.

    Parameters
    ----------
    data_cfg : mapping or DictConfig
        The ``data`` node: ``name``, ``source``, ``seed``, ``preprocess``, ``image``, ``augment``,
        ``splits`` and the source's own settings.
    data_dir : path
        Root data folder (``paths.data_dir``).
    workers : int
        Processes for the augmentation fits.
    progress : bool
        Show progress bars.
    figures : bool
        Also draw the sample sheet and the augmentation figure.
    metrics_path : path, optional
        Also write :func:`dataset_metrics` there (JSON, for DVC).

    Returns
    -------
    BuildResult
    """
    data = data_cfg
    if isinstance(data_cfg, DictConfig):
        data = OmegaConf.to_container(data_cfg, resolve=True)
    settings = read_data_settings(data)
    workers = integer(workers, "workers")
    seed, n_points, image = settings.seed, settings.preprocess.n_points, settings.image
    data_dir = Path(data_dir)

    timings: dict[str, float] = {}
    clock = time.perf_counter()

    def lap(stage: str) -> None:
        nonlocal clock
        now = time.perf_counter()
        timings[stage] = round(now - clock, 3)
        clock = now
        log.info("%s: %.2f s", stage, timings[stage])

    raw, input_info = load_raw_samples(settings, data_dir, progress)
    usable, selection = select_single_stroke_alphabet(raw)
    lap("parse")
    trajs, usable, degenerate = preprocess_samples(
        usable, n_points, settings.preprocess.smooth_sigma, progress
    )
    selection["dropped_degenerate"] = degenerate
    selection["kept"] = len(usable)
    if not usable:
        raise UsageError(
            f"no usable samples in {input_info['path'] or 'the synthetic source'}: need "
            "single-stroke samples of 0-9, A-Z, a-z"
        )
    labels = np.array([char_to_label(s.char) for s in usable], dtype=np.int64)
    writers = np.array([s.writer for s in usable])
    assignment = split_writers(writers.tolist(), settings.splits, seed)
    lap("preprocess")

    split_arrays: dict[str, dict[str, np.ndarray]] = {}
    fit_stats: dict[str, Any] = {
        "enabled": bool(settings.augment.enabled) and settings.augment.per_class > 0
    }
    for split in SPLITS:
        mask = np.isin(writers, assignment[split])
        split_arrays[split] = {
            "traj": trajs[mask],
            "label": labels[mask],
            "writer": writers[mask],
            "augmented": np.zeros(mask.sum(), dtype=bool),
            "parent": np.full(mask.sum(), -1, dtype=np.int64),
        }
    if fit_stats["enabled"]:
        train = split_arrays["train"]
        result = augment(
            train["traj"],
            train["label"],
            settings.augment,
            seed=seed,
            workers=workers,
            progress=progress,
        )
        timing_keys = ("fit_seconds", "fit_seconds_mean")  # wall times: not in the manifest
        fit_stats.update({k: v for k, v in result.stats.items() if k not in timing_keys})
        timings.update({k: round(result.stats[k], 4) for k in timing_keys if k in result.stats})
        n_aug = len(result.labels)
        split_arrays["train"] = {
            "traj": np.concatenate([train["traj"], result.trajectories]),
            "label": np.concatenate([train["label"], result.labels.astype(np.int64)]),
            "writer": np.concatenate([train["writer"], train["writer"][result.parent]]),
            "augmented": np.concatenate([train["augmented"], np.ones(n_aug, dtype=bool)]),
            "parent": np.concatenate([train["parent"], result.parent.astype(np.int64)]),
        }
    lap("fit_augment")

    for split in SPLITS:
        arrays = split_arrays[split]
        images = np.zeros((len(arrays["traj"]), image.size, image.size), np.uint8)
        starts = range(0, len(images), _RENDER_CHUNK)
        for i in tqdm(starts, desc=f"render {split}", disable=not progress, leave=False):
            chunk = arrays["traj"][i : i + _RENDER_CHUNK]
            ink = render_batch(chunk, image.size, image.stroke_width, image.margin)
            images[i : i + _RENDER_CHUNK] = np.round(ink * 255).astype(np.uint8)
        arrays["image"] = images
        arrays["traj"] = arrays["traj"].reshape(len(arrays["traj"]), -1).astype(np.float32)
    lap("render")

    final = data_dir / "prepared" / settings.name
    # the metrics file is renamed into place last (outer block), after the dataset folder
    with contextlib.ExitStack() as stack:
        metrics_tmp = stack.enter_context(atomic_path(metrics_path)) if metrics_path else None
        tmp = stack.enter_context(staged_folder(final))
        for split in SPLITS:
            save_split(tmp / f"{split}.npz", split_arrays[split])
        manifest = _manifest(
            data, settings, input_info, selection, assignment, split_arrays, fit_stats
        )
        write_json(tmp / "manifest.json", manifest)
        # the code that built it, apart from the manifest: a run fact, left out of DVC's hash of
        # the folder (.dvcignore), so that the same data built from another commit hash the same
        write_json(tmp / PROVENANCE, provenance())
        lap("write")
        if figures:
            from prg.data.figures import write_dataset_figures

            write_dataset_figures(tmp / "figures", split_arrays["train"], n_points, seed)
            lap("figures")
        if metrics_tmp is not None:
            write_text(metrics_tmp, json_text(dataset_metrics(manifest)), atomic=False)
        with deferred():  # a signal cannot fall between the folder's and the metrics' renames
            stack.close()
    return BuildResult(final, manifest, timings)


def _manifest(data, settings, input_info, selection, assignment, split_arrays, fit_stats):
    counts = {
        split: {
            "total": len(arrays["label"]),
            "originals": int((~arrays["augmented"]).sum()),
            "augmented": int(arrays["augmented"].sum()),
            "writers": len(assignment[split]),
            "per_class": {
                ALPHABET[c]: int(n) for c, n in zip(*np.unique(arrays["label"], return_counts=True))
            },
        }
        for split, arrays in split_arrays.items()
    }
    size = settings.image.size
    return {
        "name": settings.name,
        "source": settings.source,
        "input": input_info,
        "selection": selection,
        "splits": assignment,
        "counts": counts,
        "augmentation": fit_stats,
        "format": {
            "files": [f"{s}.npz" for s in SPLITS],
            "traj": f"float32 (N, {2 * settings.preprocess.n_points}), "
            f"{TRAJ_LAYOUT} x1, y1, x2, y2, ...; centred, max |coord| = 1, y up",
            "image": f"uint8 (N, {size}, {size}), ink 0..255 (divide by 255 for [0, 1])",
            "label": "int64 (N,), 0-9 -> 0..9, A-Z -> 10..35, a-z -> 36..61",
        },
        "config": data,
    }


def provenance() -> dict[str, Any]:
    """The run facts of a build (``provenance.json``): the package and the git commit."""
    return {"code_version": {"prg": prg.__version__, "git_commit": git_commit()}}


def dataset_metrics(manifest: dict[str, Any]) -> dict[str, Any]:
    """Small summary of a manifest for DVC metrics: counts and augmentation quality."""
    aug = manifest["augmentation"]
    out = {f"{s}_samples": c["total"] for s, c in manifest["counts"].items()}
    out.update({f"{s}_writers": c["writers"] for s, c in manifest["counts"].items()})
    for key in ("failure_rate", "snr_db_mean", "snr_db_median"):
        if key in aug:
            out[f"augment_{key}"] = aug[key]
    return out
