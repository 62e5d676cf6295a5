"""Benchmark the dataset build: wall time per stage for the full synthetic set.

Reference 1: the issue's budget, the whole build in 5 minutes on 2 cores (ratio = time / budget).
Reference 2: rendering, our vectorised distance-field renderer against Pillow's line drawing
(ImageDraw at 4x supersampling, box-filtered down to 28x28) on the same trajectories, same run.

Usage: ``python benchmarks/bench_prepare.py [--per-class 1000] [--writers 60] [--workers 2]``
Prints a table and writes ``benchmarks/results/bench_prepare.json``.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

from prg.commands.cli import compose_config
from prg.data.build import build_dataset
from prg.data.preprocess import _to_image_coords, render_batch
from prg.data.store import load_split
from prg.files import write_json

BUDGET_S = 300.0
RESULTS = Path(__file__).parent / "results"


def pil_render(trajs: np.ndarray, size=28, width=2.0, margin=2.0, factor=4) -> np.ndarray:
    """Reference renderer: Pillow lines with round joints at ``factor`` x, box-downsampled."""
    from PIL import Image, ImageDraw

    pts = _to_image_coords(trajs, size, width, margin) * factor
    out = np.empty((len(trajs), size, size), dtype=np.float32)
    for i, p in enumerate(pts):
        img = Image.new("L", (size * factor, size * factor), 0)
        ImageDraw.Draw(img).line(
            [tuple(q) for q in p], fill=255, width=int(width * factor), joint="curve"
        )
        out[i] = np.asarray(img.resize((size, size), Image.Resampling.BOX), np.float32) / 255
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per-class", type=int, default=None, help="default: the config's")
    parser.add_argument("--writers", type=int, default=60)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--render-n", type=int, default=5000)
    args = parser.parse_args()

    overrides = [f"data.synthetic.n_writers={args.writers}"]
    if args.per_class is not None:
        overrides.append(f"data.augment.per_class={args.per_class}")
    cfg = compose_config("prepare", overrides)
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        result = build_dataset(cfg.data, tmp, workers=args.workers, progress=True)
        total = time.perf_counter() - start
        t0 = time.perf_counter()
        train = load_split(result.out_dir / "train.npz")
        load_s = time.perf_counter() - t0
    timings = dict(result.timings)
    fit = timings.pop("fit_seconds", 0.0)
    fit_mean = timings.pop("fit_seconds_mean", 0.0)
    fit_augment = timings.pop("fit_augment")
    stages = {
        "parse": timings["parse"],
        "preprocess": timings["preprocess"],
        "fit": fit,
        "augment": round(fit_augment - fit, 3),
        "render": timings["render"],
        "write": timings["write"],
        "figures": timings.get("figures", 0.0),
    }

    trajs = train["traj"][: args.render_n].reshape(-1, 100, 2).astype(np.float64)
    t0 = time.perf_counter()
    ours = render_batch(trajs)
    ours_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    ref = pil_render(trajs)
    ref_s = time.perf_counter() - t0

    counts = result.manifest["counts"]
    report = {
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version()},
        "config": vars(args),
        "samples": {s: c["total"] for s, c in counts.items()},
        "stages_s": stages,
        "total_s": round(total, 2),
        "budget_s": BUDGET_S,
        "load_train_split_s": round(load_s, 3),
        "total_over_budget": round(total / BUDGET_S, 3),
        "augmentation": {
            k: result.manifest["augmentation"].get(k)
            for k in ("n_fits", "failure_rate", "snr_db_mean", "snr_db_median")
        }
        | {"fit_ms_mean": round(1000 * fit_mean, 2)},
        "render": {
            "n": len(trajs),
            "ours_per_s": round(len(trajs) / ours_s, 1),
            "pillow_per_s": round(len(trajs) / ref_s, 1),
            "ours_over_pillow": round(ref_s / ours_s, 3),
            "mean_abs_pixel_diff": round(float(np.abs(ours - ref).mean()), 4),
        },
    }
    print(
        f"\nDataset build, synthetic, {sum(report['samples'].values())} samples "
        f"({report['samples']}), {args.workers} workers"
    )
    print(f"{'stage':<12}{'seconds':>10}")
    for stage, sec in stages.items():
        print(f"{stage:<12}{sec:>10.2f}")
    print(f"{'total':<12}{total:>10.2f}   budget {BUDGET_S:.0f} s -> ratio {total / BUDGET_S:.2f}")
    print(f"load train split ({len(train['label'])} samples): {load_s:.2f} s (target < 1 s)")
    r = report["render"]
    print(
        f"\nRender {r['n']} images: ours {r['ours_per_s']:.0f}/s, Pillow 4x supersampled "
        f"{r['pillow_per_s']:.0f}/s, ratio ours/Pillow {r['ours_over_pillow']:.2f} "
        f"(mean |pixel diff| {r['mean_abs_pixel_diff']})"
    )
    RESULTS.mkdir(exist_ok=True)
    out = RESULTS / "bench_prepare.json"
    write_json(out, report)
    print(f"\nwrote {out}")


if __name__ == "__main__":
    main()
