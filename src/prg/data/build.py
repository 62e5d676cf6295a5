"""Build a prepared dataset: read a source, preprocess, split by writer, augment, render, write.

:func:`build_dataset` is the pure task behind ``prg-prepare``. It writes everything into a
temporary folder beside the target and renames it into place at the end, so an interrupted or
failed build leaves the previous dataset (or nothing) — never a half-written one.
"""

from __future__ import annotations

import contextlib
import logging
import os
import subprocess
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm.auto import tqdm

import prg
from prg.data.alphabet import ALPHABET, char_to_label
from prg.data.preprocess import TRAJ_LAYOUT, preprocess_stroke, render_batch
from prg.data.samples import RawSample
from prg.data.splits import SPLITS, split_writers
from prg.data.store import save_split
from prg.data.uji import select_single_stroke_alphabet
from prg.errors import UsageError
from prg.files import atomic_path, json_text, sha256_file, staged_folder, write_json, write_text
from prg.signals import deferred

log = logging.getLogger(__name__)

SOURCES = ("synthetic", "uji")
_RENDER_CHUNK = 2048  # trajectories per progress step of the render stage


@dataclass
class BuildResult:
    """What a build produced: the final folder, its manifest, and wall time per stage (s)."""

    out_dir: Path
    manifest: dict[str, Any]
    timings: dict[str, float] = field(default_factory=dict)


def _plain(cfg: Any) -> Any:
    """OmegaConf node or mapping -> plain Python containers."""
    try:
        from omegaconf import DictConfig, ListConfig, OmegaConf

        if isinstance(cfg, DictConfig | ListConfig):
            return OmegaConf.to_container(cfg, resolve=True)
    except ImportError:  # pragma: no cover - omegaconf is a dependency
        pass
    return cfg


def _positive_int(value: Any, name: str, minimum: int = 1) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        raise UsageError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def _number(value: Any, name: str, minimum: float | None = None, strict: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.number):
        raise UsageError(f"{name} must be a number, got {value!r}")
    value = float(value)
    if not np.isfinite(value) or (
        minimum is not None and (value <= minimum if strict else value < minimum)
    ):
        bound = f"> {minimum}" if strict else f">= {minimum}"
        raise UsageError(f"{name} must be a finite number {bound}, got {value!r}")
    return value


def load_raw_samples(
    data: Mapping[str, Any], data_dir: Path, progress: bool
) -> tuple[list[RawSample], dict[str, Any]]:
    """Read the configured source; returns the raw samples and a description of the input."""
    source = data.get("source")
    if source == "synthetic":
        from prg.data.synthetic import SyntheticSettings, generate

        syn = dict(data.get("synthetic") or {})
        for key in ("fonts", "slant", "width", "size", "rotation_deg", "roundness", "jitter"):
            if key in syn:
                syn[key] = tuple(syn[key])
        syn.setdefault("seed", data.get("seed", 0))
        try:
            cfg = SyntheticSettings(**syn)
        except TypeError as err:
            raise UsageError(f"data.synthetic: {err}") from None
        _positive_int(cfg.n_writers, "data.synthetic.n_writers")
        _positive_int(cfg.samples_per_char, "data.synthetic.samples_per_char")
        samples = generate(cfg)
        return samples, {"kind": "synthetic", "sha256": cfg.fingerprint(), "path": None}
    if source == "uji":
        from prg.data.download import UJI_SHA256, UJI_URL, resolve_uji_path
        from prg.data.uji import read_uji

        path = resolve_uji_path(
            data.get("uji_path"),
            data_dir,
            bool(data.get("download", False)),
            data.get("uji_url") or UJI_URL,
            data.get("uji_sha256") or UJI_SHA256,
            progress=progress,
        )
        samples = read_uji(path)
        return samples, {"kind": "uji", "sha256": sha256_file(path), "path": str(path)}
    raise UsageError(f"unknown data source {source!r}: accepted are {list(SOURCES)}")


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


def git_commit() -> str:
    """Commit of the code that runs (``+dirty`` when src/ or conf/ have uncommitted changes),
    or ``"unknown"`` outside a git checkout."""
    where = Path(prg.__file__).parent

    def git(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run(["git", *args], cwd=where, capture_output=True, text=True, timeout=5)

    try:
        head = git("rev-parse", "HEAD")
        if head.returncode != 0:
            return "unknown"
        top = git("rev-parse", "--show-toplevel").stdout.strip()
        dirty = git("status", "--porcelain", "--", f"{top}/src", f"{top}/conf").stdout.strip()
        return head.stdout.strip() + ("+dirty" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        return "unknown"


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
    data = _plain(data_cfg)
    if not isinstance(data, Mapping):
        raise UsageError("the data config must be a mapping (conf/data/*.yaml)")
    name = str(data.get("name") or "")
    if not name or "/" in name or name.startswith("."):
        raise UsageError(f"data.name {name!r} must be a plain folder name")
    seed = _positive_int(data.get("seed", 0), "data.seed", minimum=0)
    workers = _positive_int(workers, "workers")
    pre = data.get("preprocess") or {}
    n_points = _positive_int(pre.get("n_points", 100), "data.preprocess.n_points", minimum=2)
    smooth_sigma = _number(pre.get("smooth_sigma", 1.0), "data.preprocess.smooth_sigma", 0.0)
    img = data.get("image") or {}
    size = _positive_int(img.get("size", 28), "data.image.size", minimum=4)
    stroke_width = _number(img.get("stroke_width", 2.0), "data.image.stroke_width", 0.0, True)
    margin = _number(img.get("margin", 2.0), "data.image.margin", 0.0)
    if 2 * margin + stroke_width >= size:
        raise UsageError(f"data.image: 2*margin + stroke_width must be < size ({size})")
    aug = data.get("augment") or {}
    aug_enabled = bool(aug.get("enabled", True))
    per_class = _positive_int(aug.get("per_class", 1000), "data.augment.per_class", minimum=0)
    data_dir = Path(data_dir)

    timings: dict[str, float] = {}
    clock = time.perf_counter()

    def lap(stage: str) -> None:
        nonlocal clock
        now = time.perf_counter()
        timings[stage] = round(now - clock, 3)
        clock = now
        log.info("%s: %.2f s", stage, timings[stage])

    raw, input_info = load_raw_samples(data, data_dir, progress)
    usable, selection = select_single_stroke_alphabet(raw)
    lap("parse")
    trajs, usable, degenerate = preprocess_samples(usable, n_points, smooth_sigma, progress)
    selection["dropped_degenerate"] = degenerate
    selection["kept"] = len(usable)
    if not usable:
        raise UsageError(
            f"no usable samples in {input_info['path'] or 'the synthetic source'}: need "
            "single-stroke samples of 0-9, A-Z, a-z"
        )
    labels = np.array([char_to_label(s.char) for s in usable], dtype=np.int64)
    writers = np.array([s.writer for s in usable])
    assignment = split_writers(writers.tolist(), data.get("splits") or {}, seed)
    lap("preprocess")

    split_arrays: dict[str, dict[str, np.ndarray]] = {}
    fit_stats: dict[str, Any] = {"enabled": aug_enabled and per_class > 0}
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
        from prg.data.augment import augment

        train = split_arrays["train"]
        result = augment(
            train["traj"],
            train["label"],
            per_class=per_class,
            seed=seed,
            workers=workers,
            progress=progress,
            snr_target_db=_number(aug.get("snr_target_db", 20.0), "data.augment.snr_target_db"),
            max_components=_positive_int(
                aug.get("max_components", 15), "data.augment.max_components"
            ),
            amplitude=_number(aug.get("amplitude", 0.1), "data.augment.amplitude", 0.0),
            rotation_deg=_number(aug.get("rotation_deg", 5.0), "data.augment.rotation_deg", 0.0),
            sweep=_number(aug.get("sweep", 0.05), "data.augment.sweep", 0.0),
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
        images = np.zeros((len(arrays["traj"]), size, size), np.uint8)
        starts = range(0, len(images), _RENDER_CHUNK)
        for i in tqdm(starts, desc=f"render {split}", disable=not progress, leave=False):
            ink = render_batch(arrays["traj"][i : i + _RENDER_CHUNK], size, stroke_width, margin)
            images[i : i + _RENDER_CHUNK] = np.round(ink * 255).astype(np.uint8)
        arrays["image"] = images
        arrays["traj"] = arrays["traj"].reshape(len(arrays["traj"]), -1).astype(np.float32)
    lap("render")

    final = data_dir / "prepared" / name
    # the metrics file is renamed into place last (outer block), after the dataset folder
    with contextlib.ExitStack() as stack:
        metrics_tmp = stack.enter_context(atomic_path(metrics_path)) if metrics_path else None
        tmp = stack.enter_context(staged_folder(final))
        for split in SPLITS:
            save_split(tmp / f"{split}.npz", split_arrays[split])
        manifest = _manifest(
            data, name, input_info, selection, assignment, split_arrays, fit_stats, size
        )
        write_json(tmp / "manifest.json", manifest)
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


def _manifest(data, name, input_info, selection, assignment, split_arrays, fit_stats, size):
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
    return {
        "name": name,
        "source": data["source"],
        "input": input_info,
        "selection": selection,
        "splits": assignment,
        "counts": counts,
        "augmentation": fit_stats,
        "format": {
            "files": [f"{s}.npz" for s in SPLITS],
            "traj": f"float32 (N, {2 * (data.get('preprocess') or {}).get('n_points', 100)}), "
            f"{TRAJ_LAYOUT} x1, y1, x2, y2, ...; centred, max |coord| = 1, y up",
            "image": f"uint8 (N, {size}, {size}), ink 0..255 (divide by 255 for [0, 1])",
            "label": "int64 (N,), 0-9 -> 0..9, A-Z -> 10..35, a-z -> 36..61",
        },
        "config": data,
        "code_version": {"prg": prg.__version__, "git_commit": git_commit()},
    }


def dataset_metrics(manifest: dict[str, Any]) -> dict[str, Any]:
    """Small summary of a manifest for DVC metrics: counts and augmentation quality."""
    aug = manifest["augmentation"]
    out = {f"{s}_samples": c["total"] for s, c in manifest["counts"].items()}
    out.update({f"{s}_writers": c["writers"] for s, c in manifest["counts"].items()})
    for key in ("failure_rate", "snr_db_mean", "snr_db_median"):
        if key in aug:
            out[f"augment_{key}"] = aug[key]
    return out
