"""``python -m prg.commands.paper_scale``'s run: prepare the dataset if needed, train the families
and the coherence classifiers concurrently, evaluate, and keep the record (``paper_scale.json``).

The package's docstring (:mod:`prg.commands.paper_scale`) says what it writes where.
"""

from __future__ import annotations

import argparse
import os
import shlex
import sys
import time
from pathlib import Path
from typing import Any

from prg.commands.cli import handle_signals
from prg.commands.paper_scale.device import resolve_device
from prg.commands.paper_scale.jobs import (
    check_overrides,
    common_overrides,
    eval_overrides,
    module_job,
    train_overrides,
)
from prg.commands.paper_scale.options import COMMAND, parse_args
from prg.errors import PRGError, UsageError
from prg.files import write_json
from prg.processes import Console, duration, run_stage
from prg.signals import Interrupted

__all__ = ["DATA_NAME", "main", "run", "summary"]

DATA_NAME = "synthetic"


def run(args: argparse.Namespace, console: Console) -> dict[str, Any]:
    """Prepare (if needed), train, evaluate; returns the timings written to the JSON."""
    from prg.commands.cli import check_output

    root = check_output(Path(args.root), "--root")
    accelerator, device_name = resolve_device(args.device)
    import torch

    train_cfgs = {
        f: check_overrides(
            f"--train-set ({f})",
            "train",
            train_overrides(args, root, f, accelerator)
            + common_overrides(args, root, f"train-{f}"),
        )
        for f in args.families
    }
    eval_cfg = check_overrides(
        "--eval-set",
        "evaluate",
        eval_overrides(args, root, accelerator) + common_overrides(args, root, "e"),
    )
    data_dir = Path(eval_cfg.paths.data_dir)
    if args.skip_train:
        missing = [f for f in args.families if not (root / "models" / f / "model.ckpt").is_file()]
        if missing:
            raise UsageError(
                f"--skip-train: no {root / 'models' / missing[0] / 'model.ckpt'}: train first"
            )
    first = train_cfgs[args.families[0]]
    timings: dict[str, Any] = {
        "device": device_name,
        "accelerator": accelerator,
        "torch": torch.__version__,
        "cpu_count": os.cpu_count(),
        "families": args.families,
        "profile": args.profile,
        "settings": {
            "max_epochs": first.trainer.max_epochs,
            "limit_train_batches": first.trainer.limit_train_batches,
            "limit_val_batches": first.trainer.limit_val_batches,
            "batch_size": {f: c.model.batch_size for f, c in train_cfgs.items()},
            "lr": {f: c.model.module.optimizer.lr for f, c in train_cfgs.items()},
            "precision": first.trainer.precision,
            "k_marginal": args.k_marginal,
            "k_conditional": args.k_conditional,
            "n_test": args.n_test,
            "n_test_likelihood": args.n_test_likelihood or args.n_test,
            "seed": args.seed,
            "num_workers": args.num_workers,
        },
        "command": f"python -m {COMMAND} {shlex.join(args.argv)}".strip(),
        "stages": {},
        "status": "running",
    }
    report_dir = Path(eval_cfg.report_dir)
    begin = time.perf_counter()
    try:
        _stages(args, root, data_dir, accelerator, timings, console)
        timings["fit"] = _fit_costs(root, args.families)  # also the models --skip-train reuses
        _tag_evaluate_run(eval_cfg, args.profile)
        timings["status"] = "ok"
    except (PRGError, Interrupted) as err:
        # the record of a run that did not finish goes beside its logs; the reports folder keeps
        # the last complete run's
        failed = isinstance(err, PRGError)
        timings["status"] = f"failed: {err}" if failed else f"stopped by {err}"
        timings["total_seconds"] = round(time.perf_counter() - begin, 2)
        write_json(root / "logs" / "paper_scale.json", timings)
        raise
    timings["total_seconds"] = round(time.perf_counter() - begin, 2)
    timings["reports"] = {
        name: str(report_dir / f"{name}.md") for name in ("table1", "coherence", "robustness")
    }
    write_json(report_dir / "paper_scale.json", timings)
    return timings


def _stages(
    args: argparse.Namespace,
    root: Path,
    data_dir: Path,
    accelerator: str,
    timings: dict[str, Any],
    console: Console,
) -> None:
    cores = os.cpu_count() or 1
    stages = timings["stages"]
    if not (data_dir / "prepared" / DATA_NAME / "manifest.json").is_file():
        console.say(f"no dataset in {data_dir / 'prepared' / DATA_NAME}: preparing it")
        overrides = [
            f"data={DATA_NAME}",
            "progress=false",
            f"workers={cores}",
            f"metrics_path={root / 'reports' / 'prepare' / 'metrics.json'}",
            *common_overrides(args, root, "prepare"),
        ]
        overrides = [o for o in overrides if not o.startswith(("logger.", "seed="))]
        overrides += args.prepare_set
        job = module_job("prepare", "prg.commands.prepare", overrides, root / "logs/prepare.log")
        begin = time.perf_counter()
        run_stage("prepare", [job], console, args.progress_every)
        stages["prepare"] = {"seconds": round(time.perf_counter() - begin, 2)}

    if not args.skip_train:
        trainings = list(args.families)
        threads = args.threads or max(1, cores // (len(trainings) + 1))
        jobs = [
            module_job(
                f,
                "prg.commands.train",
                train_overrides(args, root, f, accelerator)
                + common_overrides(args, root, f"train-{f}"),
                root / f"logs/train-{f}.log",
                threads,
            )
            for f in trainings
        ]
        classifier = [
            "parts=[classifiers]",
            "progress=false",
            f"classifier.dir={root / 'models' / 'classifiers'}",
            *args.eval_set,
            *common_overrides(args, root, "classifiers"),
        ]
        jobs.append(
            module_job(
                "classifiers",
                "prg.commands.evaluate",
                classifier,
                root / "logs/classifiers.log",
                threads,
            )
        )
        console.say(
            f"training {', '.join(trainings)} and the coherence classifiers concurrently "
            f"({accelerator}, {threads} CPU thread(s) each)"
        )
        begin = time.perf_counter()
        try:
            run_stage("train", jobs, console, args.progress_every)
        finally:
            stages["train"] = {
                "seconds": round(time.perf_counter() - begin, 2),
                "jobs": {j.name: j.seconds for j in jobs if j.started},
            }

    evaluate = [
        *eval_overrides(args, root, accelerator),
        *common_overrides(args, root, "evaluate"),
    ]
    job = module_job("evaluate", "prg.commands.evaluate", evaluate, root / "logs/evaluate.log")
    begin = time.perf_counter()
    try:
        run_stage("evaluate", [job], console, args.progress_every)
    finally:
        stages["evaluate"] = {"seconds": round(time.perf_counter() - begin, 2)}


def _fit_costs(root: Path, families: list[str]) -> dict[str, dict[str, float]]:
    """Each finished training's fit cost from its ``metrics.json``: CPU seconds (all threads),
    wall seconds, epochs and steps (the wall time of concurrent jobs overstates a lone run's)."""
    import json

    out = {}
    for family in families:
        path = root / "models" / family / "metrics.json"
        if path.is_file():
            metrics = json.loads(path.read_text())
            out[family] = {
                k: metrics.get(k) for k in ("fit_cpu_s", "fit_wall_s", "epochs", "steps")
            }
    return out


def _tag_evaluate_run(cfg: Any, profile: str) -> None:
    """Tag the newest ``<profile>-evaluate`` run with its profile, like the training runs."""
    from prg.tracking import task_client

    client, experiment = task_client(cfg)
    runs = client.search_runs(
        [experiment],
        filter_string=f"tags.mlflow.runName = '{cfg.run_name}'",
        order_by=["attributes.start_time DESC"],
        max_results=1,
    )
    if runs:
        client.set_tag(runs[0].info.run_id, "prg.experiment", profile)


def summary(timings: dict[str, Any], root: Path, report_dir: Path) -> str:
    lines = [
        "",
        f"Profile {timings['profile']} done in {duration(timings['total_seconds'])} on {timings['device']} "
        f"({timings['accelerator']}).",
    ]
    for stage, info in timings["stages"].items():
        detail = ""
        if "jobs" in info:
            detail = "  (" + ", ".join(f"{k} {duration(v)}" for k, v in info["jobs"].items()) + ")"
        lines.append(f"  {stage:<9} {duration(info['seconds']):>10}{detail}")
    lines += [
        f"Table I:    {report_dir / 'table1.md'}",
        f"Coherence:  {report_dir / 'coherence.md'}",
        f"Robustness: {report_dir / 'robustness.md'}",
        f"Models:     {root / 'models'}/<family>/model.ckpt",
        f"Timings:    {report_dir / 'paper_scale.json'}",
        f"Logs:       {root / 'logs'}/",
        f"Runs:       mlflow ui --backend-store-uri {timings['tracking_uri']}   "
        f"(experiment {timings['experiment']})",
    ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    console = Console()
    # `make`, a scheduler or Ctrl-C stopping us: the training jobs are stopped too (run's stop)
    with handle_signals(COMMAND):
        _main(argv, console)


def _main(argv: list[str] | None, console: Console) -> None:
    try:
        args = parse_args(sys.argv[1:] if argv is None else argv)
        timings = run(args, console)
        timings["experiment"] = args.experiment_name
        timings["tracking_uri"] = args.tracking_uri or "sqlite:///mlruns.db"
        report_dir = Path(timings["reports"]["table1"]).parent
        console.say(summary(timings, Path(args.root), report_dir))
    except PRGError as err:
        print(f"{COMMAND}: error: {err}", file=sys.stderr, flush=True)
        sys.exit(err.exit_code)
