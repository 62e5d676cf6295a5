"""The command lines of the processes ``python -m prg.commands.paper_scale`` runs: ``prg-prepare``,
one ``prg-train`` per family, ``prg-evaluate`` for the classifiers and for the reports.

Every child gets the overrides of :func:`common_overrides` (seed, logs, data, MLflow store) besides
its own (:func:`train_overrides`, :func:`eval_overrides`); :func:`check_overrides` composes a
config with them before anything starts, so that a bad ``--train-set`` or ``--eval-set`` is one
line. :func:`module_job` makes the :class:`prg.processes.Job` that runs one.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Any

from prg.errors import UsageError
from prg.processes import Job

__all__ = [
    "BAR_REFRESH_STEPS",
    "check_overrides",
    "common_overrides",
    "eval_overrides",
    "module_job",
    "train_overrides",
]

# The Lightning progress bar is redrawn every this many steps: often enough to follow, rare
# enough to cost nothing (a redraw formats every logged metric).
BAR_REFRESH_STEPS = 25


def _child_env(threads: int | None) -> dict[str, str]:
    """This process's environment, unbuffered, with ``threads`` BLAS/OpenMP threads if given."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    if threads:
        env["OMP_NUM_THREADS"] = str(threads)
        env["MKL_NUM_THREADS"] = str(threads)
    return env


def common_overrides(args: argparse.Namespace, root: Path, job: str) -> list[str]:
    """What every child is given: the seed, its logs under ``root``, the data and the MLflow
    store, experiment and artifacts."""
    out = [
        f"seed={args.seed}",
        f"paths.log_dir={root / 'logs'}",
        f"hydra.run.dir={root}/logs/{job}",
    ]
    if args.data_dir:
        out.append(f"paths.data_dir={args.data_dir}")
    if args.tracking_uri:
        out.append(f"logger.tracking_uri={args.tracking_uri}")
    out += [
        f"logger.experiment_name={args.experiment_name}",
        f"logger.artifact_location={root / 'mlartifacts'}",
    ]
    return out


def train_overrides(args: argparse.Namespace, root: Path, family: str, accelerator: str) -> list:
    """``prg-train`` overrides for one family (without the ``hydra.*`` ones: :func:`train_argv`)."""
    out = [
        f"model={family}",
        f"experiment={args.profile}",
        f"export_dir={root / 'models' / family}",
        f"checkpoint_dir={root / 'checkpoints' / family}",
        f"trainer.accelerator={'gpu' if accelerator == 'cuda' else 'cpu'}",
        f"data.loader.num_workers={args.num_workers}",
        "+callbacks.progress._target_=lightning.pytorch.callbacks.TQDMProgressBar",
        f"+callbacks.progress.refresh_rate={BAR_REFRESH_STEPS}",
    ]
    for key, value in (
        ("max_epochs", args.epochs),
        ("limit_train_batches", args.limit_train_batches),
        ("limit_val_batches", args.limit_val_batches),
    ):
        if value is not None:
            out.append(f"trainer.{key}={value}")
    return out + args.train_overrides[family]


def eval_overrides(args: argparse.Namespace, root: Path, accelerator: str) -> list[str]:
    n_test = "null" if args.n_test is None else args.n_test
    n_likelihood = args.n_test_likelihood or n_test
    out = [
        f"families=[{','.join(args.families)}]",
        f"models_dir={root / 'models'}",
        f"report_dir={root / 'reports'}",
        f"classifier.dir={root / 'models' / 'classifiers'}",
        f"likelihood.k_marginal={args.k_marginal}",
        f"likelihood.k_conditional={args.k_conditional}",
        f"n_test={n_test}",
        f"likelihood.n_test={n_likelihood}",
        f"run_name={args.profile}-evaluate",
    ]
    if _evaluate_has("device"):  # prg-evaluate runs on the CPU unless it offers a device
        out.append(f"device={accelerator}")
    return out + list(args.eval_set)


def _evaluate_has(key: str) -> bool:
    from prg.commands.cli import compose_config

    return key in compose_config("evaluate", [])


def _split(overrides: list[str]) -> tuple[list[str], list[str]]:
    hydra = [o for o in overrides if o.lstrip("+~").startswith("hydra.")]
    return [o for o in overrides if o not in hydra], hydra


def check_overrides(name: str, config: str, overrides: list[str]) -> Any:
    """Compose ``conf/<config>.yaml`` with ``overrides`` (not ``hydra.*``): one line if bad."""
    from prg.commands.cli import compose_config

    plain, _ = _split(overrides)
    try:
        return compose_config(config, plain)
    except Exception as err:  # Hydra raises several types; all mean a bad override
        message = " ".join(str(err).split())
        cut = message.find("Set the environment variable HYDRA_FULL_ERROR")
        raise UsageError(f"{name}: {(message[:cut] if cut > 0 else message).strip()}") from None


def module_job(
    name: str, module: str, overrides: list[str], log: Path, threads: int | None = None
) -> Job:
    """``python -m module overrides`` as the job ``name``, logging to ``log`` (``threads``: the
    child's BLAS/OpenMP thread count; ``None`` leaves it to the environment)."""
    return Job(name, [sys.executable, "-m", module, *overrides], log, _child_env(threads))
