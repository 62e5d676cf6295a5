"""The options of ``python -m prg.commands.paper_scale``: one line and exit 2 when bad.

:func:`parse_args` checks what argparse cannot (the families, ``--train-set``'s ``FAMILY:``
prefix, the ``KEY=VALUE`` shapes) and adds ``argv``, the per-family ``train_overrides`` and the
profile's defaults for ``--root`` and ``--experiment-name``.
"""

from __future__ import annotations

import argparse

from prg.checks import FAMILIES, PAPER_FAMILIES
from prg.errors import UsageError, UsageParser

__all__ = ["COMMAND", "PROFILES", "build_parser", "parse_args"]

COMMAND = "prg.commands.paper_scale"
PROFILES = ("paper", "converged")


def _number(text: str) -> int | float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text!r}")
    return int(value) if value.is_integer() and "." not in text else value


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {text!r}")
    return value


def build_parser() -> argparse.ArgumentParser:
    p = UsageParser(
        prog=f"python -m {COMMAND}",
        description="Train the four families at the paper's settings concurrently on one GPU, "
        "then evaluate them at the paper's K, into their own folder (make paper).",
    )
    p.add_argument(
        "--families",
        default=",".join(PAPER_FAMILIES),
        help="comma-separated families to train and evaluate (default: the paper's four; "
        f"accepted: {', '.join(FAMILIES)})",
    )
    p.add_argument(
        "--profile",
        choices=PROFILES,
        default="paper",
        help="training profile, experiment=PROFILE (default paper; converged: the fast recipe "
        "until validation stops improving)",
    )
    p.add_argument("--root", help="output folder (default: the profile's name)")
    p.add_argument(
        "--device",
        choices=("cuda", "cpu", "auto"),
        default="cuda",
        help="cuda (default; refused when torch sees no GPU), cpu, or auto",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of every run (default 0)")
    p.add_argument("--data-dir", help="paths.data_dir (default: the project's data/)")
    budget = p.add_argument_group("budget (default: the paper's)")
    budget.add_argument("--epochs", type=_positive_int, help="trainer.max_epochs (paper: 50)")
    budget.add_argument("--limit-train-batches", type=_number, help="trainer.limit_train_batches")
    budget.add_argument("--limit-val-batches", type=_number, help="trainer.limit_val_batches")
    budget.add_argument(
        "--k-marginal", type=_positive_int, default=1000, help="K for log p(x_m) (paper: 1000)"
    )
    budget.add_argument(
        "--k-conditional",
        type=_positive_int,
        default=5000,
        help="K for log p(x_a | x_b) (paper: 5000)",
    )
    budget.add_argument(
        "--n-test", type=_positive_int, help="test samples evaluated (default: the whole split)"
    )
    budget.add_argument(
        "--n-test-likelihood",
        type=_positive_int,
        help="test samples for Table I only (default: --n-test); coherence and robustness "
        "keep --n-test",
    )
    run = p.add_argument_group("processes")
    run.add_argument(
        "--num-workers",
        type=int,
        default=0,
        help="data.loader.num_workers of each training (default 0: the data are in-memory "
        "tensors, gathered in ~0.2 ms per batch in the main process; workers add IPC)",
    )
    run.add_argument(
        "--threads",
        type=_positive_int,
        help="CPU threads per concurrent process (default: the cores shared among them)",
    )
    run.add_argument(
        "--progress-every",
        type=float,
        default=30.0,
        help="seconds between progress lines of each process (default 30)",
    )
    run.add_argument(
        "--skip-train",
        action="store_true",
        help="evaluate the models already in ROOT/models (after a failed evaluation)",
    )
    run.add_argument("--tracking-uri", help="MLflow store (default: the project's mlruns.db)")
    run.add_argument("--experiment-name", help="MLflow experiment (default: prg-PROFILE)")
    run.add_argument(
        "--train-set",
        action="append",
        default=[],
        metavar="[FAMILY:]KEY=VALUE",
        help="extra prg-train override, for every family or one (repeatable)",
    )
    run.add_argument(
        "--eval-set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="extra prg-evaluate override (repeatable; also given to the classifiers job)",
    )
    run.add_argument(
        "--prepare-set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="extra prg-prepare override, used when the dataset has to be prepared first",
    )
    return p


def parse_args(argv: list[str]) -> argparse.Namespace:
    args = build_parser().parse_args(argv)
    args.argv = list(argv)
    families = [f.strip() for f in args.families.split(",") if f.strip()]
    unknown = [f for f in families if f not in FAMILIES]
    if unknown or not families:
        raise UsageError(
            f"--families {args.families!r}: unknown {', '.join(map(repr, unknown)) or 'none'}; "
            f"choose from {', '.join(FAMILIES)}"
        )
    if len(set(families)) != len(families):
        raise UsageError(f"--families {args.families!r}: a family is named twice")
    args.families = families
    args.root = args.root or args.profile
    args.experiment_name = args.experiment_name or f"prg-{args.profile}"
    if args.num_workers < 0:
        raise UsageError(f"--num-workers must be >= 0, got {args.num_workers}")
    if args.progress_every <= 0:
        raise UsageError(f"--progress-every must be > 0, got {args.progress_every}")
    per_family: dict[str, list[str]] = {f: [] for f in families}
    for item in args.train_set:
        key, eq, _ = item.partition("=")
        if not eq or not key:
            raise UsageError(f"--train-set {item!r}: expected [FAMILY:]KEY=VALUE")
        family, colon, _ = key.partition(":")
        if colon:
            if family not in FAMILIES:
                raise UsageError(f"--train-set {item!r}: unknown family {family!r}")
            if family in per_family:
                per_family[family].append(item.split(":", 1)[1])
        else:
            for overrides in per_family.values():
                overrides.append(item)
    args.train_overrides = per_family
    for option, items in (("--eval-set", args.eval_set), ("--prepare-set", args.prepare_set)):
        for item in items:
            if "=" not in item or item.startswith("="):
                raise UsageError(f"{option} {item!r}: expected KEY=VALUE")
    return args
