"""``python -m prg.commands.paper_scale`` (``make paper``, ``make converged``): train and evaluate the four
families under one profile, in one command.

``--profile paper`` (default, ``make paper``) trains at the paper's settings (``prg-train
model=<family> experiment=paper``: Adam 1e-4, batch 128 / 64 (MUSE), 50 epochs, fp32), sized for
one GPU; ``--profile converged`` (``make converged``) trains the fast recipe until validation stops
improving (``experiment=converged``), sized for a CPU. The four trainings run as concurrent
processes, together with the two coherence classifiers, then ``prg-evaluate`` runs at the paper's
K (1000 marginals / 5000 conditionals), on the whole test split unless ``--n-test`` (all
metrics) or ``--n-test-likelihood`` (Table I only) say otherwise. Everything goes under its own
folder (``--root``, default the profile's name), never into the demo's ``models/`` and
``reports/``::

    paper/models/<family>/model.ckpt, metrics.json   the best checkpoint of each training
                                                     (metrics.json: fit CPU and wall seconds)
    paper/models/classifiers/                        the coherence classifiers
    paper/checkpoints/<family>/                      best.ckpt, last.ckpt (resumable)
    paper/reports/table1.md, coherence.md, ...       prg-evaluate's reports
    paper/reports/paper_scale.json                   wall time per stage, fit CPU time per
                                                     family, device, settings
    paper/logs/<job>.log                             each process's whole output
    paper/logs/paper_scale.json                      the record of a failed or stopped run

MLflow runs go to the project's store (``--tracking-uri`` for another) in the experiment
``prg-<profile>``; the training runs carry the tag ``prg.experiment=<profile>``, the evaluation
run is named ``<profile>-evaluate``.

Each process's output is shown prefixed by its name (``[muse] ...``), its progress bar at most
every ``--progress-every`` seconds. A process that fails stops the others and the command with
one line naming it, its last error line and its log (exit 1; 2 when the failure was a usage
error); bad options are one line with exit 2 before anything starts.

The options for a tiny budget (``--epochs``, ``--limit-train-batches``, ``--k-marginal`` ...)

Modules
-------
:mod:`prg.commands.paper_scale.options`
    The options, checked before anything starts.
:mod:`prg.commands.paper_scale.device`
    ``--device`` resolved and named.
:mod:`prg.commands.paper_scale.jobs`
    The children's command lines (``prg-prepare``, ``prg-train``, ``prg-evaluate``).
:mod:`prg.commands.paper_scale.command`
    The run: stages, record, summary, :func:`main`.
:mod:`prg.processes`
    The concurrent child processes, their prefixed output and their stopping.
"""

from __future__ import annotations

from prg.checks import PAPER_FAMILIES as FAMILIES  # trained by default
from prg.commands.paper_scale.command import DATA_NAME, main, run, summary
from prg.commands.paper_scale.device import cpu_name, resolve_device
from prg.commands.paper_scale.jobs import (
    BAR_REFRESH_STEPS,
    check_overrides,
    eval_overrides,
    train_overrides,
)
from prg.commands.paper_scale.options import COMMAND, PROFILES, build_parser, parse_args
from prg.processes import STOP_GRACE_S, Console, Job, StageFailed, run_stage, start, stop

__all__ = [
    "BAR_REFRESH_STEPS",
    "COMMAND",
    "DATA_NAME",
    "FAMILIES",
    "PROFILES",
    "STOP_GRACE_S",
    "Console",
    "Job",
    "StageFailed",
    "build_parser",
    "check_overrides",
    "cpu_name",
    "eval_overrides",
    "main",
    "parse_args",
    "resolve_device",
    "run",
    "run_stage",
    "start",
    "stop",
    "summary",
    "train_overrides",
]
