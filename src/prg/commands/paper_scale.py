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
run the same path on a CPU in seconds (``--device cpu``; tests/test_paper_scale.py).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import platform
import re
import shlex
import signal
import subprocess
import sys
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from prg.checks import FAMILIES
from prg.commands.cli import handle_signals
from prg.errors import PRGError, UsageError
from prg.files import write_json
from prg.signals import Interrupted, deferred

COMMAND = "prg.commands.paper_scale"
PROFILES = ("paper", "converged")
DATA_NAME = "synthetic"
# The Lightning progress bar is redrawn every this many steps: often enough to follow, rare
# enough to cost nothing (a redraw formats every logged metric).
BAR_REFRESH_STEPS = 25
# Seconds a stopped process gets to shut down after SIGINT before it is killed.
STOP_GRACE_S = 10.0

_PROGRESS = re.compile(r"\d+/(\d+|\?) \[|\d+%\|")
_ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")
# Lines not worth a terminal line (still in the log): an advertisement, a warning every epoch.
_NOISE = ("💡 Tip:", "`weights_only` was not set")
_ERROR_LINE = re.compile(r"^(prg-\w+: error: |[A-Za-z_][\w.]*(Error|Exception|Interrupt)\b)")


# ---- options ---------------------------------------------------------------------------------
class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2 (argparse prints usage too)
        raise UsageError(message)


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
    p = _Parser(
        prog=f"python -m {COMMAND}",
        description="Train the four families at the paper's settings concurrently on one GPU, "
        "then evaluate them at the paper's K, into their own folder (make paper).",
    )
    p.add_argument(
        "--families",
        default=",".join(FAMILIES),
        help="comma-separated families to train and evaluate (default: all four)",
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


# ---- the device ------------------------------------------------------------------------------
def cpu_name() -> str:
    """The CPU's model name (``/proc/cpuinfo``), with its core count."""
    name = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                name = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{name or platform.processor() or platform.machine()} ({os.cpu_count()} cores)"


def resolve_device(device: str) -> tuple[str, str]:
    """``(accelerator, device name)``: ``cuda`` needs a GPU that torch can use."""
    import torch

    cuda = torch.cuda.is_available()
    if device == "cuda" and not cuda:
        build = "a CPU-only build" if torch.version.cuda is None else f"CUDA {torch.version.cuda}"
        raise UsageError(
            f"--device cuda: torch {torch.__version__} ({build}) sees no GPU; the paper scale "
            "is sized for one (install a CUDA build of torch there), or pass --device cpu to "
            "run it on the CPU anyway (hours: README 'Paper scale on a GPU')"
        )
    if device == "cpu" or not cuda:
        return "cpu", cpu_name()
    return "cuda", torch.cuda.get_device_name(0)


# ---- processes -------------------------------------------------------------------------------
@dataclass
class Job:
    """One child process: its command, log file, output tail and wall time."""

    name: str
    argv: list[str]
    log: Path
    env: dict[str, str]
    proc: subprocess.Popen | None = None
    started: float = 0.0
    ended: float | None = None
    lines: deque = field(default_factory=lambda: deque(maxlen=200))
    progress: str = ""
    shown: str = ""
    reader: threading.Thread | None = None

    @property
    def seconds(self) -> float:
        return round((self.ended or time.perf_counter()) - self.started, 2)

    def error_line(self) -> str:
        """The child's last error line (``prg-train: error: ...``, ``ValueError: ...``)."""
        lines = [line for line in self.lines if line.strip()]
        for line in reversed(lines):
            if _ERROR_LINE.match(line.strip()):
                return line.strip()
        useful = [line for line in lines if "HYDRA_FULL_ERROR" not in line]
        return useful[-1].strip() if useful else "no output"


class Console:
    """Prints the children's lines with their name in front, one writer at a time."""

    def __init__(self) -> None:
        self.lock = threading.Lock()

    def say(self, text: str, prefix: str = "") -> None:
        with self.lock:
            print(f"[{prefix}] {text}" if prefix else text, flush=True)


def _short_bar(text: str) -> str:
    """A tqdm line without its bar glyphs: ``Epoch 3:  45% 500/1099 [00:10<00:12, ...]``."""
    return re.sub(r"\|[^|]*\|", " ", text).strip()


def _take(job: Job, console: Console, raw: bytes) -> None:
    """One piece of the child's output: a progress bar is kept for later, a line printed."""
    text = _ANSI.sub("", raw.decode("utf-8", "replace")).rstrip()
    bar = _PROGRESS.search(text)
    if bar:  # a bar, perhaps with a warning written right after it
        close = text.find("]", bar.end())
        job.progress = _short_bar(text if close < 0 else text[: close + 1])
        text = "" if close < 0 else text[close + 1 :]
    text = text.strip()
    if text and not text.startswith(_NOISE):
        job.lines.append(text)
        console.say(text, job.name)


def _pump(job: Job, console: Console) -> None:
    """Copy the child's output to its log and take it apart at carriage returns and newlines."""
    assert job.proc is not None and job.proc.stdout is not None
    buffer = b""
    with open(job.log, "ab") as log:
        while chunk := job.proc.stdout.read1(65536):
            log.write(chunk)
            log.flush()
            *parts, buffer = re.split(rb"[\r\n]", buffer + chunk)
            for raw in parts:
                _take(job, console, raw)
        _take(job, console, buffer)


def start(job: Job, console: Console) -> None:
    job.log.parent.mkdir(parents=True, exist_ok=True)
    job.log.write_text(f"$ {shlex.join(job.argv)}\n")
    console.say(f"start: {shlex.join(job.argv[2:])}", job.name)
    job.started = time.perf_counter()
    with deferred():  # a signal here would leave a child that `stop` does not know of
        job.proc = subprocess.Popen(
            job.argv,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL,
            env=job.env,
            start_new_session=True,  # its own process group: stopped as a whole, workers too
        )
    job.reader = threading.Thread(target=_pump, args=(job, console), daemon=True)
    job.reader.start()


def stop(jobs: list[Job]) -> list[str]:
    """Interrupt every running job's process group, kill what is left after a grace period;
    returns the names of the jobs that were still running."""
    running = [j for j in jobs if j.proc is not None and j.proc.poll() is None]
    for job in running:
        with contextlib.suppress(ProcessLookupError):  # Lightning shuts down, MLflow run KILLED
            os.killpg(job.proc.pid, signal.SIGINT)
    deadline = time.monotonic() + STOP_GRACE_S
    for job in running:
        with contextlib.suppress(subprocess.TimeoutExpired):
            job.proc.wait(timeout=max(0.1, deadline - time.monotonic()))
    for job in running:
        with contextlib.suppress(ProcessLookupError):  # also any worker left in the group
            os.killpg(job.proc.pid, signal.SIGKILL)
        job.proc.wait()
        job.ended = job.ended or time.perf_counter()
    return [j.name for j in running]


class StageFailed(PRGError):
    """A child process failed; carries the exit code to pass on (2 for its usage errors)."""

    def __init__(self, message: str, code: int):
        super().__init__(message)
        self.exit_code = code


def run_stage(stage: str, jobs: list[Job], console: Console, progress_every: float) -> None:
    """Run ``jobs`` concurrently to the end; the first failure stops the others."""
    last_shown = time.monotonic()
    try:
        for job in jobs:
            start(job, console)
        while True:
            pending = [j for j in jobs if j.ended is None]
            for job in pending:
                code = job.proc.poll()
                if code is None:
                    continue
                job.reader.join(timeout=5)  # a grandchild may hold the pipe open a moment
                job.ended = time.perf_counter()
                if code != 0:
                    stopped = stop(jobs)
                    raise StageFailed(
                        f"{stage}: {job.name} failed "
                        + (f"(exit {code})" if code > 0 else f"(killed by signal {-code})")
                        + f": {job.error_line()}"
                        + (f"; stopped {', '.join(stopped)}" if stopped else "")
                        + f"; log: {job.log}",
                        2 if code == 2 else 1,
                    )
                if job.progress and job.progress != job.shown:  # its last state, e.g. val/loss
                    job.shown = job.progress
                    console.say(job.progress, job.name)
                console.say(f"done in {_duration(job.seconds)}", job.name)
            if all(j.ended is not None for j in jobs):
                return
            if time.monotonic() - last_shown >= progress_every:
                last_shown = time.monotonic()
                for job in jobs:
                    if job.ended is None and job.progress and job.progress != job.shown:
                        job.shown = job.progress
                        console.say(job.progress, job.name)
            time.sleep(0.2)
    except Interrupted:
        stopped = stop(jobs)
        console.say(f"{stage}: interrupted; stopped {', '.join(stopped) or 'nothing'}")
        raise


# ---- the command lines -----------------------------------------------------------------------
def _child_env(threads: int | None) -> dict[str, str]:
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    if threads:
        env["OMP_NUM_THREADS"] = str(threads)
        env["MKL_NUM_THREADS"] = str(threads)
    return env


def _common(args: argparse.Namespace, root: Path, job: str) -> list[str]:
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


# ---- the command -----------------------------------------------------------------------------
def _duration(seconds: float) -> str:
    minutes, secs = divmod(round(seconds), 60)
    return f"{minutes} m {secs:02d} s" if minutes else f"{seconds:.1f} s"


def _module_job(
    name: str, module: str, overrides: list[str], log: Path, threads: int | None = None
) -> Job:
    """``python -m module overrides`` as the job ``name``, logging to ``log`` (``threads``: the
    child's BLAS/OpenMP thread count; ``None`` leaves it to the environment)."""
    return Job(name, [sys.executable, "-m", module, *overrides], log, _child_env(threads))


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
            train_overrides(args, root, f, accelerator) + _common(args, root, f"train-{f}"),
        )
        for f in args.families
    }
    eval_cfg = check_overrides(
        "--eval-set", "evaluate", eval_overrides(args, root, accelerator) + _common(args, root, "e")
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
            *_common(args, root, "prepare"),
        ]
        overrides = [o for o in overrides if not o.startswith(("logger.", "seed="))]
        overrides += args.prepare_set
        job = _module_job("prepare", "prg.commands.prepare", overrides, root / "logs/prepare.log")
        begin = time.perf_counter()
        run_stage("prepare", [job], console, args.progress_every)
        stages["prepare"] = {"seconds": round(time.perf_counter() - begin, 2)}

    if not args.skip_train:
        trainings = list(args.families)
        threads = args.threads or max(1, cores // (len(trainings) + 1))
        jobs = [
            _module_job(
                f,
                "prg.commands.train",
                train_overrides(args, root, f, accelerator) + _common(args, root, f"train-{f}"),
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
            *_common(args, root, "classifiers"),
        ]
        jobs.append(
            _module_job(
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
        *_common(args, root, "evaluate"),
    ]
    job = _module_job("evaluate", "prg.commands.evaluate", evaluate, root / "logs/evaluate.log")
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
        f"Profile {timings['profile']} done in {_duration(timings['total_seconds'])} on {timings['device']} "
        f"({timings['accelerator']}).",
    ]
    for stage, info in timings["stages"].items():
        detail = ""
        if "jobs" in info:
            detail = "  (" + ", ".join(f"{k} {_duration(v)}" for k, v in info["jobs"].items()) + ")"
        lines.append(f"  {stage:<9} {_duration(info['seconds']):>10}{detail}")
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


if __name__ == "__main__":
    main()
