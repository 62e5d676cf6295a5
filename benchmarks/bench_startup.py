"""Benchmark command start-up: whole ``prg-*`` processes against ``python -c "import torch"``.

Every case is one process of an installed console script, timed from start to exit
(``time.perf_counter`` around ``subprocess.run``), side by side in the same run with the floor,
a bare ``python -c "import torch"``: ratio = median command time / median floor time. The cases
run round-robin (floor, case 1, case 2, ..., floor, ...) ``--reps`` times after one untimed
warm-up round, so a change in the machine's load touches all of them alike.

- bad input to ``prg-write`` (an unknown key, an unknown family, a number out of range) and
  ``prg-write --help``: answered from the composed config before torch is imported;
  target <= 0.5 x the floor;
- ``prg-write text=hi``: a whole word with the defaults (an MLflow run, logged by a background
  process once the command has ended, and a Rerun recording), and with
  ``mlflow=false record=false``; target <= 2 x the floor. After every case the benchmark waits
  until any background logger is done, so none runs during the next case, and reports when
  the MLflow run was in the store;
- an unknown key given to each of the other Hydra commands (no target: their modules import
  what their tasks use at import time).

Each case is also run once with ``PYTHONPROFILEIMPORTTIME=1`` (untimed) to record whether torch
was imported, and its exit code and stderr are checked (one line for bad input). The processes
run in an empty working folder with ``PRG_ROOT`` set to a temporary project root; the working
folder must stay empty. The model is ``models/muse/model.ckpt`` of this project (``make demo``),
linked into that root, when present; else a MUSE with seeded random weights whose trajectory
decoders draw every letter as one smooth loop (random output layers draw white noise, whose
words are tens of centimetres long: a write time that says nothing about start-up).

Usage: ``python benchmarks/bench_startup.py [--reps 5]``
Prints a table and writes ``benchmarks/results/bench_startup.json``.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from prg.files import write_json

RESULTS = Path(__file__).parent / "results"
ROOT = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent
TARGET_BAD = 0.5  # bad input and --help: at most this times the floor
TARGET_WRITE = 2.0  # a whole word: at most this times the floor
OTHER_COMMANDS = ("prepare", "train", "evaluate", "dictaphone", "simulate", "export")


@dataclass(frozen=True)
class Case:
    name: str
    argv: tuple[str, ...]
    code: int  # the exit code it must end with
    target: float | None  # ratio to the floor; None: shown, not judged
    one_line: bool = False  # stderr must be exactly one line (a usage error)


def cases() -> list[Case]:
    python = (sys.executable, "-c")
    write = str(BIN / "prg-write")
    found = [
        Case("floor: python -c 'import torch'", (*python, "import torch"), 0, None),
        Case("prg-write txt=hello", (write, "txt=hello"), 2, TARGET_BAD, True),
        Case("prg-write family=musee", (write, "family=musee"), 2, TARGET_BAD, True),
        Case("prg-write temperature=-1", (write, "temperature=-1"), 2, TARGET_BAD, True),
        Case(
            "prg-write generate.temperature=-1",
            (write, "generate.temperature=-1"),
            2,
            TARGET_BAD,
            True,
        ),
        Case("prg-write --help", (write, "--help"), 0, TARGET_BAD),
        Case("prg-write text=hi", (write, "text=hi"), 0, TARGET_WRITE),
        Case(
            "prg-write text=hi mlflow=false record=false",
            (write, "text=hi", "mlflow=false", "record=false"),
            0,
            TARGET_WRITE,
        ),
    ]
    for command in OTHER_COMMANDS:
        script = str(BIN / f"prg-{command}")
        found.append(Case(f"prg-{command} txt=hello", (script, "txt=hello"), 2, None, True))
    return found


def model_root(root: Path) -> str:
    """Put a MUSE checkpoint at ``root/models/muse/model.ckpt``; returns where it came from."""
    target = root / "models" / "muse" / "model.ckpt"
    target.parent.mkdir(parents=True)
    demo = ROOT / "models" / "muse" / "model.ckpt"
    if demo.is_file():
        target.symlink_to(demo)
        return "models/muse/model.ckpt"
    import torch
    from omegaconf import OmegaConf

    from prg.commands.cli import compose_config
    from prg.models.components import TrajectoryDecoder
    from prg.models.module import PRGModule

    node = compose_config("train", ["model=muse"]).model.module
    node = OmegaConf.to_container(node, resolve=True)
    torch.manual_seed(0)
    module = PRGModule(model=node["model"], optimizer=node["optimizer"])
    # Random output layers draw white-noise letters (a 3-letter word of 80 cm, a DMP of 2000
    # bases); every letter is one smooth loop instead, so the write work is a real word's.
    turn = torch.linspace(0, 2 * torch.pi, 101)[:-1]
    loop = torch.stack([0.6 * torch.sin(turn), torch.cos(turn)], dim=1).reshape(-1)
    for decoder in module.model.modules():
        if isinstance(decoder, TrajectoryDecoder):
            torch.nn.init.zeros_(decoder.net[-1].weight)
            decoder.net[-1].bias.data.copy_(loop)
    torch.save(
        {"state_dict": module.state_dict(), "hyper_parameters": dict(module.hparams)}, target
    )
    return "random weights, every letter one smooth loop (no demo model)"


def run(case: Case, cwd: Path, env: dict[str, str]) -> tuple[float, subprocess.CompletedProcess]:
    start = time.perf_counter()
    done = subprocess.run(case.argv, cwd=cwd, env=env, capture_output=True, text=True)
    return time.perf_counter() - start, done


def settle(root: Path, timeout_s: float = 120) -> float:
    """Wait until the MLflow runs that commands handed to background loggers
    (``mlflow_background``) are logged, so a logger never runs during the next timed case;
    returns the seconds waited (the file goes when its run is in the store; on Linux, also
    until the logger process is gone)."""
    pending = root / "logs" / "pending-runs"
    start = time.perf_counter()
    while any(pending.glob("*.json")) or _loggers_running(pending):
        if time.perf_counter() - start > timeout_s:
            raise SystemExit(f"bench_startup: background MLflow logging stuck in {pending}")
        time.sleep(0.02)
    return time.perf_counter() - start


def _loggers_running(pending: Path) -> bool:
    for cmdline in Path("/proc").glob("[0-9]*/cmdline"):
        try:
            if str(pending).encode() in cmdline.read_bytes():
                return True
        except OSError:  # the process ended meanwhile
            continue
    return False


def check(case: Case, done: subprocess.CompletedProcess) -> str | None:
    """What is wrong with a run's exit code or error output; None when nothing."""
    if done.returncode != case.code:
        return f"exit code {done.returncode}, expected {case.code}: {done.stderr[-500:]}"
    if case.one_line and len(done.stderr.strip().splitlines()) != 1:
        return f"not one line: {done.stderr[-500:]}"
    return None


def imports_torch(case: Case, cwd: Path, env: dict[str, str]) -> bool:
    """Whether the case's process imports torch (``-X importtime``'s report, untimed)."""
    done = subprocess.run(
        case.argv,
        cwd=cwd,
        env={**env, "PYTHONPROFILEIMPORTTIME": "1"},
        capture_output=True,
        text=True,
    )
    return any(line.rpartition("|")[2].strip() == "torch" for line in done.stderr.splitlines())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=5, help="timed rounds")
    args = parser.parse_args()

    with tempfile.TemporaryDirectory(prefix="bench-startup-") as tmp:
        root, cwd = Path(tmp, "root"), Path(tmp, "cwd")
        cwd.mkdir()
        model = model_root(root)
        env = {**os.environ, "PRG_ROOT": str(root), "PYTHONUNBUFFERED": "1"}
        env.pop("MLFLOW_TRACKING_URI", None)  # the store under the root
        todo = cases()
        problems = {}
        torch_imported = {}
        for case in todo:  # warm-up: page cache, the MLflow store's tables
            _, done = run(case, cwd, env)
            problems[case.name] = check(case, done)
            torch_imported[case.name] = imports_torch(case, cwd, env)
            settle(root)
        times: dict[str, list[float]] = {case.name: [] for case in todo}
        logged: dict[str, list[float]] = {case.name: [] for case in todo}
        for rep in range(args.reps):
            for case in todo:
                seconds, done = run(case, cwd, env)
                waited = settle(root)
                times[case.name].append(seconds)
                logged[case.name].append(seconds + waited)
                problems[case.name] = problems[case.name] or check(case, done)
            print(f"round {rep + 1}/{args.reps} done", flush=True)
        left_in_cwd = sorted(str(p.relative_to(cwd)) for p in cwd.rglob("*"))

    floor = statistics.median(times[todo[0].name])
    rows = []
    for case in todo:
        median = statistics.median(times[case.name])
        rows.append(
            {
                "case": case.name,
                "median_s": median,
                "min_s": min(times[case.name]),
                "ratio": median / floor,
                "target_ratio": case.target,
                "torch_imported": torch_imported[case.name],
                # until its MLflow run, handed to a background logger, is in the store
                "run_logged_after_s": statistics.median(logged[case.name]),
                "problem": problems[case.name],
            }
        )

    print(
        f"\nCommand start-up, whole processes from an empty working folder, median of "
        f"{args.reps}; ratio = median / the floor's median ({floor:.2f} s) in the same run"
    )
    header = f"{'case':<46} | {'median':>8} {'min':>7} | {'ratio':>6} {'target':>7} | torch"
    print(header)
    print("-" * len(header))
    for r in rows:
        target = f"<= {r['target_ratio']:g}" if r["target_ratio"] is not None else ""
        flag = ""
        if r["target_ratio"] is not None and r["ratio"] > r["target_ratio"]:
            flag = "  < target"
        if r["problem"]:
            flag += f"  ! {r['problem'].splitlines()[0][:120]}"
        print(
            f"{r['case']:<46} | {r['median_s']:>7.2f}s {r['min_s']:>6.2f}s | {r['ratio']:>6.2f} "
            f"{target:>7} | {'yes' if r['torch_imported'] else 'no':>5}{flag}"
        )
    for r in rows:
        if r["run_logged_after_s"] - r["median_s"] > 0.5:
            print(
                f"{r['case']}: its MLflow run is in the store {r['run_logged_after_s']:.2f} s"
                " after the start (median; logged in the background after the command ended)"
            )
    if left_in_cwd:
        print(f"\n! written into the working folder: {', '.join(left_in_cwd[:10])}")

    report = {
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "torch": importlib.metadata.version("torch"),
            "processor": platform.processor() or platform.machine(),
            "load_avg_at_end": [round(x, 2) for x in os.getloadavg()],
        },
        "settings": {
            "reps": args.reps,
            "model": model,
            "target_bad_ratio": TARGET_BAD,
            "target_write_ratio": TARGET_WRITE,
        },
        "floor_s": floor,
        "rows": rows,
        "left_in_working_folder": left_in_cwd,
    }
    RESULTS.mkdir(exist_ok=True)
    out = write_json(RESULTS / "bench_startup.json", report)
    print(f"\nwrote {out}")


if __name__ == "__main__":
    main()
