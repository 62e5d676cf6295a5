"""Benchmark training throughput: PRGModule under a Lightning Trainer against a plain PyTorch loop.

For each family (cvae, avae_ts, avae_ti, muse) the same network (same class, same seed, the
family's config from ``conf/model/<family>.yaml``), the same Adam, batch size (the paper's: 128
for CVAE/AVAE, 64 for MUSE) and the same batches (one seeded DataLoader over the same in-memory
tensors) are trained twice, side by side in this run:

- plain: ``loss = model.elbo(batch)["loss"]; opt.zero_grad(); loss.backward(); opt.step()``;
- lightning: ``PRGModule`` under ``lightning.Trainer`` (CPU, no logger, no checkpointing, no
  progress bar, no model summary, no validation).

Each side runs ``--warmup`` untimed batches then ``--batches`` timed ones; the clock covers the
batch fetch and the step for both (Lightning's from the end of the last warm-up batch to the end
of the last timed batch, measured by a callback, so trainer set-up is excluded; the set-up time
is reported apart). The two sides alternate ``--reps`` times (plain, lightning, plain, ...)
and the medians are compared: ratio = lightning / plain samples per second (target >= 0.9).

Usage: ``python benchmarks/bench_train.py [--families cvae muse] [--batches 60] [--reps 3]``
Prints a table and writes ``benchmarks/results/bench_train.json``.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import statistics
import tempfile
import time
import warnings
from pathlib import Path

import lightning as L
import torch
from hydra.utils import instantiate
from omegaconf import OmegaConf

from prg.cli import compose_config
from prg.data.datamodule import PRGDataModule
from prg.models.module import PRGModule

RESULTS = Path(__file__).parent / "results"
REPO = Path(__file__).resolve().parents[1]
FAMILIES = ("cvae", "avae_ts", "avae_ti", "muse")
TARGET = 0.9


def family_config(family: str) -> dict:
    """The ``model`` node of the train config for ``family`` (module config, batch size)."""
    cfg = compose_config("train", [f"model={family}"])
    return OmegaConf.to_container(cfg.model, resolve=True)


def prepare_data(data_dir: Path | None, tmp: str) -> tuple[Path, str]:
    """The prepared dataset to read: the repository's full one if present, else a small one."""
    if data_dir is not None and (data_dir / "prepared/synthetic/manifest.json").is_file():
        return data_dir, "full prepared synthetic dataset"
    from prg.data.build import build_dataset

    cfg = compose_config("prepare", ["data.synthetic.n_writers=10", "data.augment.per_class=40"])
    build_dataset(cfg.data, tmp, workers=1, progress=False, figures=False)
    return Path(tmp), "small synthetic dataset built for the benchmark"


class StepClock(L.Callback):
    """Time from the end of batch ``warmup - 1`` to the end of batch ``warmup + n - 1``."""

    def __init__(self, warmup: int, n: int):
        self.warmup, self.n = warmup, n
        self.start = self.end = None

    def on_train_batch_end(self, trainer, pl_module, outputs, batch, batch_idx):
        if batch_idx == self.warmup - 1:
            self.start = time.perf_counter()
        elif batch_idx == self.warmup + self.n - 1:
            self.end = time.perf_counter()

    @property
    def seconds(self) -> float:
        return self.end - self.start


def run_plain(module_cfg: dict, loader, warmup: int, n: int, seed: int) -> float:
    """Seconds for ``n`` batches (fetch + step) of a plain PyTorch loop after ``warmup``."""
    torch.manual_seed(seed)
    model = instantiate(module_cfg["model"], _convert_="all")
    model.train()
    opt = instantiate(module_cfg["optimizer"])(params=model.parameters())
    start = None
    for i, batch in enumerate(loader):
        loss = model.elbo(batch)["loss"]
        opt.zero_grad()
        loss.backward()
        opt.step()
        if i == warmup - 1:
            start = time.perf_counter()
        elif i == warmup + n - 1:
            return time.perf_counter() - start
    raise RuntimeError(f"the loader ran out before {warmup + n} batches")


def run_lightning(module_cfg: dict, loader, warmup: int, n: int, seed: int) -> tuple[float, float]:
    """(seconds for the ``n`` timed batches, wall seconds of the whole ``fit`` incl. set-up)."""
    torch.manual_seed(seed)
    module_cfg = {k: v for k, v in module_cfg.items() if k != "_target_"}
    module = PRGModule(**module_cfg)
    clock = StepClock(warmup, n)
    trainer = L.Trainer(
        accelerator="cpu",
        devices=1,
        max_steps=warmup + n,
        max_epochs=-1,
        limit_val_batches=0,
        num_sanity_val_steps=0,
        logger=False,
        enable_checkpointing=False,
        enable_progress_bar=False,
        enable_model_summary=False,
        callbacks=[clock],
    )
    t0 = time.perf_counter()
    trainer.fit(module, train_dataloaders=loader)
    return clock.seconds, time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--families", nargs="+", default=list(FAMILIES), choices=FAMILIES)
    parser.add_argument("--batches", type=int, default=60, help="timed batches per run")
    parser.add_argument("--warmup", type=int, default=5, help="untimed batches per run")
    parser.add_argument("--reps", type=int, default=3, help="alternating runs per side")
    parser.add_argument(
        "--threads", type=int, default=1, help="torch threads, the same for both sides"
    )
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--data-dir", type=Path, default=REPO / "data")
    args = parser.parse_args()

    torch.set_num_threads(args.threads)
    warnings.filterwarnings("ignore", ".*does not have many workers.*")
    warnings.filterwarnings("ignore", ".*LeafSpec.*")
    warnings.filterwarnings("ignore", ".*no `val_dataloader`.*")
    logging.getLogger("lightning.pytorch").setLevel(logging.WARNING)
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        data_dir, data_source = prepare_data(args.data_dir, tmp)
        n_train = None
        for family in args.families:
            cfg = family_config(family)
            dm = PRGDataModule(
                data_dir, "synthetic", cfg["modalities"], cfg["batch_size"], seed=args.seed
            )
            dm.setup("fit")
            n_train = len(dm.datasets["train"])
            plain, light, setup = [], [], []
            for _ in range(args.reps):
                # a fresh, identically seeded loader for each run: the same batches for both
                plain.append(
                    run_plain(cfg["module"], dm.train_dataloader(), args.warmup, args.batches, 0)
                )
                step_s, fit_s = run_lightning(
                    cfg["module"], dm.train_dataloader(), args.warmup, args.batches, 0
                )
                light.append(step_s)
                setup.append(fit_s)
            samples = args.batches * cfg["batch_size"]
            plain_sps = samples / statistics.median(plain)
            light_sps = samples / statistics.median(light)
            rows[family] = {
                "batch_size": cfg["batch_size"],
                "plain_samples_per_s": round(plain_sps, 1),
                "lightning_samples_per_s": round(light_sps, 1),
                "ratio": round(light_sps / plain_sps, 3),
                "paired_ratios": [round(p / q, 3) for p, q in zip(plain, light)],
                "plain_ms_per_step": [round(1000 * s / args.batches, 2) for s in plain],
                "lightning_ms_per_step": [round(1000 * s / args.batches, 2) for s in light],
                "lightning_fit_wall_s": [round(s, 2) for s in setup],
            }
            r = rows[family]
            print(
                f"{family}: plain {r['plain_ms_per_step']} ms/step, "
                f"lightning {r['lightning_ms_per_step']} ms/step",
                flush=True,
            )

    report = {
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "torch": torch.__version__,
            "lightning": L.__version__,
            "processor": platform.processor() or platform.machine(),
            "load_avg_at_end": [round(x, 2) for x in os.getloadavg()],
        },
        "settings": {
            "threads": args.threads,
            "warmup_batches": args.warmup,
            "timed_batches": args.batches,
            "reps": args.reps,
            "order": "alternating plain, lightning; medians compared",
            "data": data_source,
            "train_samples": n_train,
            "target_ratio": TARGET,
        },
        "families": rows,
    }
    print(
        f"\nTraining throughput, {args.batches} timed batches after {args.warmup} warm-up, "
        f"median of {args.reps} alternating runs, {args.threads} thread(s)"
    )
    header = f"{'family':<9}{'batch':>6}{'plain/s':>11}{'lightning/s':>13}{'ratio':>8}"
    print(header)
    for family, r in rows.items():
        flag = "" if r["ratio"] >= TARGET else "  < target"
        print(
            f"{family:<9}{r['batch_size']:>6}{r['plain_samples_per_s']:>11.0f}"
            f"{r['lightning_samples_per_s']:>13.0f}{r['ratio']:>8.3f}{flag}"
        )
    RESULTS.mkdir(exist_ok=True)
    out = RESULTS / "bench_train.json"
    out.write_text(json.dumps(report, indent=2) + "\n")
    print(f"\nwrote {out}")


if __name__ == "__main__":
    main()
