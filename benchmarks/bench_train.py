"""Benchmark training: Lightning overhead, the fast recipe's speed techniques, time to quality.

Three parts (``--parts``, all by default), each compared with its reference in the same run:

1. ``throughput`` — PRGModule under a Lightning Trainer against a plain PyTorch loop (below).
2. ``techniques`` — MUSE samples per second of a plain loop with each speed technique of the fast
   recipe (``conf/experiment/_recipe_.yaml``) added in turn, against the paper's plain fp32 loop
   at batch 64, on the same batches: batch 128, bf16 autocast, channels-last images,
   ``torch.compile`` (``--compile``; measured, not part of the recipe). Ratio = technique / fp32.
3. ``quality`` — CPU minutes (process CPU time, all threads, evaluation excluded) until MUSE's
   T-from-S coherence (posterior mean, whole test split, case twins folded) first reaches
   ``--target`` (0.85): ``prg-train``'s ``experiment=quick`` (the recipe, the demo's budget)
   against the paper's recipe (Adam 1e-4, batch 64, fp32, constant rate), the paper's run capped
   at ``--cap`` times ours (reported as "not reached in N min" if it does not get there).
   Ratio = paper / ours (target >= 5). Needs the full prepared dataset and the evaluation
   classifiers (``make demo`` or ``prg-prepare`` + ``prg-evaluate parts=[classifiers]``).

Part 1:

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

Usage: ``python benchmarks/bench_train.py [--parts throughput techniques quality]
[--families cvae muse] [--batches 60] [--reps 3] [--compile] [--cap 5]``
Prints a table per part and writes ``benchmarks/results/bench_train.json`` (the parts not run
keep their previous results).
"""

from __future__ import annotations

import argparse
import json
import logging
import math
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

from prg.checks import FAMILIES
from prg.commands.cli import compose_config
from prg.data.datamodule import PRGDataModule
from prg.files import write_json
from prg.models.module import PRGModule

RESULTS = Path(__file__).parent / "results"
REPO = Path(__file__).resolve().parents[1]
TARGET = 0.9
PARTS = ("throughput", "techniques", "quality")


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


def bare_trainer(clock: L.Callback, **settings) -> L.Trainer:
    """A CPU Trainer that only trains: no validation, logger, checkpoints, bar or summary."""
    return L.Trainer(
        accelerator="cpu",
        devices=1,
        limit_val_batches=0,
        num_sanity_val_steps=0,
        logger=False,
        enable_checkpointing=False,
        enable_progress_bar=False,
        enable_model_summary=False,
        callbacks=[clock],
        **settings,
    )


def run_lightning(module_cfg: dict, loader, warmup: int, n: int, seed: int) -> tuple[float, float]:
    """(seconds for the ``n`` timed batches, wall seconds of the whole ``fit`` incl. set-up)."""
    torch.manual_seed(seed)
    module_cfg = {k: v for k, v in module_cfg.items() if k != "_target_"}
    module = PRGModule(**module_cfg)
    clock = StepClock(warmup, n)
    trainer = bare_trainer(clock, max_steps=warmup + n, max_epochs=-1)
    t0 = time.perf_counter()
    trainer.fit(module, train_dataloaders=loader)
    return clock.seconds, time.perf_counter() - t0


# ---- part 2: speed techniques -----------------------------------------------------------------
TECHNIQUES = {  # name -> (batch size, bf16 autocast, channels-last images, torch.compile)
    "fp32, batch 64 (paper)": (64, False, False, False),
    "batch 128": (128, False, False, False),
    "batch 128 + bf16 autocast": (128, True, False, False),
    "batch 128 + bf16 + channels-last": (128, True, True, False),
    "batch 128 + bf16 + torch.compile": (128, True, False, True),
}


def run_technique(
    module_cfg: dict, train: dict, technique: tuple, n: int, warmup: int
) -> tuple[float, float]:
    """(samples per second, mean loss of the timed batches) of a plain MUSE loop over ``n``
    batches drawn from ``train``: the loss shows whether a technique changes what is learnt."""
    batch_size, bf16, channels_last, compiled = technique
    torch.manual_seed(0)
    model = instantiate(module_cfg["model"], _convert_="all")
    memory_format = torch.channels_last if channels_last else torch.contiguous_format
    model = model.to(memory_format=memory_format)
    opt = instantiate(module_cfg["optimizer"])(params=model.parameters())
    elbo = torch.compile(model.elbo) if compiled else model.elbo
    order = torch.randperm(len(train["label"]), generator=torch.Generator().manual_seed(0))
    start, losses = None, []
    for i in range(warmup + n):
        rows = order[i * batch_size : (i + 1) * batch_size]
        batch = {k: v[rows] for k, v in train.items()}
        batch["image"] = batch["image"].float().div(255).unsqueeze(1)
        batch["image"] = batch["image"].contiguous(memory_format=memory_format)
        with torch.autocast("cpu", dtype=torch.bfloat16, enabled=bf16):
            loss = elbo(batch)["loss"]
        opt.zero_grad()
        loss.backward()
        opt.step()
        if i == warmup - 1:
            start = time.perf_counter()
        elif i >= warmup:
            losses.append(loss.item())
    return n * batch_size / (time.perf_counter() - start), statistics.fmean(losses)


def techniques_part(data_dir: Path, args) -> dict:
    from prg.data.store import load_split

    arrays = load_split(data_dir / "prepared/synthetic/train.npz")
    train = {
        "traj": torch.from_numpy(arrays["traj"]).float(),
        "image": torch.from_numpy(arrays["image"]),
        "label": torch.from_numpy(arrays["label"].astype("int64")),
    }
    cfg = family_config("muse")
    names = [t for t in TECHNIQUES if args.compile or not TECHNIQUES[t][3]]
    speeds: dict[str, list[float]] = {t: [] for t in names}
    losses: dict[str, float] = {}
    for _ in range(args.reps):  # alternate the techniques so drifts in load hit all of them
        for name in names:
            speed, losses[name] = run_technique(
                cfg["module"], train, TECHNIQUES[name], args.batches, args.warmup
            )
            speeds[name].append(speed)
            print(f"  {name}: {speed:.0f} samples/s, loss {losses[name]:.1f}", flush=True)
    reference = statistics.median(speeds[names[0]])
    rows = {
        name: {
            "samples_per_s": round(statistics.median(v), 1),
            "runs": [round(x, 1) for x in v],
            "ratio": round(statistics.median(v) / reference, 3),
            "mean_loss_timed_batches": round(losses[name], 2),
        }
        for name, v in speeds.items()
    }
    print(f"\nMUSE training throughput by technique ({args.threads} thread(s), plain loop)")
    print(f"{'technique':<36}{'samples/s':>11}{'ratio':>8}{'loss':>9}")
    for name, r in rows.items():
        print(
            f"{name:<36}{r['samples_per_s']:>11.0f}{r['ratio']:>8.2f}"
            f"{r['mean_loss_timed_batches']:>9.1f}"
        )
    return {"family": "muse", "reference": names[0], "techniques": rows}


# ---- part 3: time to quality ------------------------------------------------------------------
DECODINGS = {"imputed": None, "mean": 0}  # name -> impute steps (None: --impute-steps)


class QualityClock(L.Callback):
    """Every ``every`` steps: T-from-S coherence (folded) on the test split under each decoding
    (``imputed``: as ``prg-write`` decodes, after ``impute_steps`` rounds of imputing the
    missing modalities; ``mean``: the paper's posterior mean), against the process CPU time
    spent training so far (the checks' own CPU time is excluded). Records when each of
    ``levels`` is first reached per decoding; stops the run once the imputed decoding reaches
    ``stop_at`` or ``cap_s`` CPU seconds are spent."""

    def __init__(self, test, classifier, every, levels, stop_at, cap_s, impute_steps):
        self.test, self.classifier, self.every = test, classifier, every
        self.levels, self.stop_at, self.cap_s = sorted(levels), stop_at, cap_s
        self.steps = {d: impute_steps if s is None else s for d, s in DECODINGS.items()}
        self.history: list[dict] = []
        self.reached_s: dict[str, dict[float, float]] = {d: {} for d in DECODINGS}
        self._start = self._excluded = 0.0

    def on_train_start(self, trainer, pl_module):
        self._start, self._excluded = time.process_time(), 0.0

    def cpu_s(self) -> float:
        return time.process_time() - self._start - self._excluded

    def on_train_batch_end(self, trainer, pl_module, outputs, batch, batch_idx):
        step = trainer.global_step
        last = trainer.fit_loop.epoch_loop.batch_progress.is_last_batch and (
            trainer.current_epoch + 1 >= trainer.max_epochs
        )
        if step % self.every and not last:
            return
        spent = self.cpu_s()
        paused = time.process_time()
        values = {
            d: coherence_t_from_s(pl_module.model, self.test, self.classifier, steps)
            for d, steps in self.steps.items()
        }
        self._excluded += time.process_time() - paused
        self.history.append({"step": step, "cpu_s": round(spent, 1), **values})
        print(
            f"  step {step}: {spent / 60:.1f} CPU min, T from S "
            + ", ".join(f"{d} {v:.3f}" for d, v in values.items()),
            flush=True,
        )
        for d, value in values.items():
            for level in self.levels:
                if value >= level:
                    self.reached_s[d].setdefault(level, spent)
        if self.stop_at in self.reached_s["imputed"] or spent >= self.cap_s:
            trainer.should_stop = True


def coherence_t_from_s(model, test: dict, classifier, impute_steps: int) -> float:
    """Folded coherence of trajectories decoded from the test labels."""
    from prg.evaluation.classifiers import folded_accuracy
    from prg.evaluation.coherence import generated_classes

    was_training = model.training
    model.eval()
    try:
        predicted = generated_classes(
            model, "traj", ("label",), test, {"traj": classifier}, impute_steps=impute_steps
        )
    finally:
        model.train(was_training)
    return folded_accuracy(predicted, test["label"])


def run_to_quality(profile: str, data_dir: Path, clock: QualityClock, tmp: str) -> dict:
    """Train MUSE with ``experiment=<profile>`` until ``clock`` stops it or the budget ends."""
    cfg = compose_config("train", ["model=muse", f"experiment={profile}"])
    module = PRGModule(**{k: v for k, v in cfg.model.module.items() if k != "_target_"})
    dm = PRGDataModule(data_dir, "synthetic", list(cfg.model.modalities), cfg.model.batch_size)
    trainer = bare_trainer(
        clock,
        precision=cfg.trainer.precision,
        max_epochs=cfg.trainer.max_epochs,
        limit_train_batches=cfg.trainer.limit_train_batches,
        default_root_dir=tmp,
    )
    trainer.fit(module, datamodule=dm)
    return {
        "profile": profile,
        "batch_size": cfg.model.batch_size,
        "precision": cfg.trainer.precision,
        "lr": cfg.model.module.optimizer.lr,
        "max_epochs": cfg.trainer.max_epochs,
        "steps": trainer.global_step,
        "cpu_min_to": {
            d: {str(k): round(v / 60, 2) for k, v in reached.items()}
            for d, reached in clock.reached_s.items()
        },
        "cpu_min_spent": round(clock.cpu_s() / 60, 2),
        "history": clock.history,
    }


def _said(run: dict, decoding: str, level: float) -> str:
    minutes = run["cpu_min_to"][decoding].get(str(level))
    if minutes is not None:
        return f"{minutes:.1f} CPU min"
    return f"not reached in {run['cpu_min_spent']:.1f} CPU min"


def quality_part(data_dir: Path, args, tmp: str) -> dict:
    """Ours (``experiment=quick``) against the paper's recipe, CPU minutes to each level.

    Ours runs its whole budget unless its imputed decoding reaches ``--target``. The compared
    level is the highest of ``--target`` and ``--levels`` that ours reached (imputed decoding);
    the paper's run then goes until that level or ``--cap`` times ours to it, so "not reached"
    within the cap means at least ``--cap`` times slower."""
    import numpy as np

    from prg.data.store import load_split
    from prg.evaluation.classifiers import load_classifier

    path = args.data_dir.parent / "models/classifiers/traj.pt"
    if not path.is_file():
        raise SystemExit(f"bench_train: {path} missing: run `prg-evaluate parts=[classifiers]`")
    classifier = load_classifier(path)[0]
    arrays = load_split(data_dir / "prepared/synthetic/test.npz")
    test = {"label": torch.from_numpy(arrays["label"].astype(np.int64))}
    levels = sorted({args.target, *args.levels})

    def clock(every: int, stop_at: float, cap_s: float) -> QualityClock:
        return QualityClock(test, classifier, every, levels, stop_at, cap_s, args.impute_steps)

    print(f"ours (experiment=quick) until T from S >= {args.target}", flush=True)
    ours = run_to_quality("quick", data_dir, clock(args.every, args.target, math.inf), tmp)
    reached = [level for level in levels if str(level) in ours["cpu_min_to"]["imputed"]]
    compared = max(reached) if reached else args.target
    budget = ours["cpu_min_to"]["imputed"].get(str(compared), ours["cpu_min_spent"])
    cap_s = args.cap * budget * 60
    print(f"paper (experiment=paper) until {compared}, capped at {cap_s / 60:.1f} CPU min")
    # the paper's batch is half ours: the same number of samples between checks
    paper = run_to_quality("paper", data_dir, clock(args.every * 2, compared, cap_s), tmp)
    speedups: dict[str, dict] = {d: {} for d in DECODINGS}
    for d in DECODINGS:
        for level in levels:
            ours_min = ours["cpu_min_to"][d].get(str(level))
            if ours_min is None:
                continue
            paper_min = paper["cpu_min_to"][d].get(str(level))
            speedups[d][str(level)] = {
                "ratio": round((paper_min or paper["cpu_min_spent"]) / ours_min, 2),
                "lower_bound": paper_min is None,  # the paper's run ended before reaching it
            }
    result = {
        "target": args.target,
        "levels": levels,
        "compared_level": compared,
        "metric": "MUSE T-from-S coherence, whole test split, case twins folded",
        "decodings": {
            "imputed": f"posterior mean after {args.impute_steps} rounds of imputing the "
            "missing modalities (prg-write's decoding)",
            "mean": "the paper's posterior mean",
        },
        "cpu_time": f"process CPU time, all {args.threads} torch thread(s), checks excluded",
        "cap_multiple": args.cap,
        "ours": ours,
        "paper": paper,
        "speedup": speedups,  # paper's CPU minutes / ours, per decoding and level ours reached
    }
    print(f"\nCPU minutes to MUSE T-from-S coherence (folded), {args.threads} thread(s)")
    print(f"{'decoding':<9}{'level':>6}  {'ours (quick)':<28}{'paper recipe':<28}{'speed-up':>9}")
    for d in DECODINGS:
        for level in levels:
            s = speedups[d].get(str(level))
            ratio = "-" if s is None else f"{'>= ' if s['lower_bound'] else ''}{s['ratio']:.1f}x"
            print(
                f"{d:<9}{level:>6}  {_said(ours, d, level):<28}{_said(paper, d, level):<28}"
                f"{ratio:>9}"
            )
    return result


def throughput_part(data_dir: Path, data_source: str, args) -> dict:
    """Part 1: Lightning against a plain loop for each family."""
    rows = {}
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
    return report


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", nargs="+", default=list(PARTS), choices=PARTS)
    parser.add_argument("--families", nargs="+", default=list(FAMILIES), choices=FAMILIES)
    parser.add_argument("--batches", type=int, default=60, help="timed batches per run")
    parser.add_argument("--warmup", type=int, default=5, help="untimed batches per run")
    parser.add_argument("--reps", type=int, default=3, help="alternating runs per side")
    parser.add_argument(
        "--threads", type=int, default=1, help="torch threads, the same for both sides"
    )
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--data-dir", type=Path, default=REPO / "data")
    parser.add_argument("--compile", action="store_true", help="also time torch.compile")
    parser.add_argument("--target", type=float, default=0.85, help="T-from-S coherence to reach")
    parser.add_argument(
        "--levels",
        type=float,
        nargs="*",
        default=[0.6, 0.7, 0.8],
        help="lower coherence levels also timed (the comparison falls back to them)",
    )
    parser.add_argument("--every", type=int, default=110, help="steps between quality checks")
    parser.add_argument("--cap", type=float, default=5.0, help="paper's budget, x ours")
    parser.add_argument(
        "--impute-steps", type=int, default=20, help="rounds of imputation (prg-write's default)"
    )
    args = parser.parse_args()

    torch.set_num_threads(args.threads)
    warnings.filterwarnings("ignore", ".*does not have many workers.*")
    warnings.filterwarnings("ignore", ".*LeafSpec.*")
    warnings.filterwarnings("ignore", ".*no `val_dataloader`.*")
    logging.getLogger("lightning.pytorch").setLevel(logging.WARNING)
    out = RESULTS / "bench_train.json"
    report = json.loads(out.read_text()) if out.is_file() else {}
    with tempfile.TemporaryDirectory() as tmp:
        data_dir, data_source = prepare_data(args.data_dir, tmp)
        if "throughput" in args.parts:
            report.update(throughput_part(data_dir, data_source, args))
        if "techniques" in args.parts:
            report["techniques"] = techniques_part(data_dir, args)
        if "quality" in args.parts:
            if data_source != "full prepared synthetic dataset":
                raise SystemExit("bench_train: the quality part needs the full prepared dataset")
            report["time_to_quality"] = quality_part(data_dir, args, tmp)
    report["machine"] = {
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
        "torch": torch.__version__,
        "lightning": L.__version__,
        "processor": platform.processor() or platform.machine(),
        "load_avg_at_end": [round(x, 2) for x in os.getloadavg()],
    }
    RESULTS.mkdir(exist_ok=True)
    write_json(out, report)  # atomic: a killed run leaves the old JSON whole
    print(f"\nwrote {out}")


if __name__ == "__main__":
    main()
