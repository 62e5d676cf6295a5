"""Benchmark the DMP: prg.pipeline.dmp against the `movement-primitives` package's DMP.

Both sides fit one DMP to the same word-like trajectory (a cursive-like curve 20 cm wide, 4 cm
tall, 12 loops per 1000 points, sampled uniformly in time over ``tau = 1`` with a minimum-jerk
time course, so it starts and ends at rest, the same curve as ``tests/prg/pipeline/test_dmp.py``) and roll
it out on the demonstration's time grid, side by side in this run:

- ours: ``fit_dmp(points, tau=1, n_basis=N)`` (fourth-order differences, one banded ridge solve,
  default regularisation) and ``rollout(dmp)`` (exact discretisation + ``lfilter``, no Python
  loop per step);
- theirs: ``movement_primitives.dmp.DMP(n_dims=2, execution_time=1, dt=1/(n-1),
  n_weights_per_dim=N)``, ``imitate(T, points)`` (their default: no regularisation) and
  ``open_loop()`` (their default integrator, ``rk4-cython``: one RK4 step per sample, driven
  from Python). Their grid ``arange(0, 1 + dt, dt)`` can carry one sample past ``t = 1``; the
  first ``n`` samples are compared.

For every word length (500/1000/2000 points) and basis count (50/100/300 per dimension) the two
sides alternate ``--reps`` times (ours, theirs, ours, ...); fit and rollout are timed separately
with ``time.perf_counter`` and medians are compared: ratio = their time / our time. The target
(>= 10 at equal or better error) is judged on fit + rollout, the time from a demonstration to
its reproduction; fit and rollout ratios are shown separately too. A second table compares at
equal error: for each word length, our smallest basis count (of ``--search``) whose RMSE is at
most theirs at their largest basis count, against that configuration of theirs. RMSE is the root mean squared distance (cm) between the rollout
and the demonstration. BLAS is limited to ``--threads`` threads on both sides (ours limits its
fit and rollout to one BLAS thread itself, see ``prg.pipeline.dmp._one_blas_thread``).

Note: `movement-primitives` 0.9.1 imports ``pytransform3d`` in ``movement_primitives.dmp``'s
``__init__`` (for its Cartesian DMPs) without declaring it; when that is missing, the plain
``DMP`` is loaded from its module ``movement_primitives.dmp._dmp`` directly (same code).

Usage: ``python benchmarks/bench_dmp.py [--points 500 1000 2000] [--basis 50 100 300] [--reps 5]``
Prints a table and writes ``benchmarks/results/bench_dmp.json``.
"""

from __future__ import annotations

import argparse
import importlib
import os
import platform
import statistics
import sys
import time
import types
from pathlib import Path

import numpy as np
import scipy
from threadpoolctl import threadpool_limits

from prg.files import write_json
from prg.pipeline.dmp import fit_dmp, rollout

RESULTS = Path(__file__).parent / "results"
TARGET = 10.0


def word_like(n: int, loops: int, width: float = 20.0, height: float = 4.0) -> np.ndarray:
    """The test curve of ``tests/prg/pipeline/test_dmp.py``: ``loops`` loops, ``width`` x ``height`` cm."""
    t = np.linspace(0.0, 1.0, n)
    s = 10 * t**3 - 15 * t**4 + 6 * t**5
    angle = 2 * np.pi * loops * s
    amplitude = 0.55 + 0.45 * np.sin(2 * np.pi * 2.3 * s + 0.7) ** 2
    x = s - 0.045 * np.sin(angle)
    y = amplitude * (1 - np.cos(angle)) + 0.15 * np.sin(np.pi * s)
    x = (x - x.min()) / np.ptp(x) * width
    y = (y - y.min()) / np.ptp(y) * height
    return np.column_stack([x, y])


def load_their_dmp() -> tuple[type, str]:
    """``movement_primitives``' DMP class and how it was imported."""
    try:
        from movement_primitives.dmp import DMP

        return DMP, "movement_primitives.dmp"
    except ModuleNotFoundError as exc:
        if exc.name != "pytransform3d":
            raise
        import movement_primitives

        package = types.ModuleType("movement_primitives.dmp")
        package.__path__ = [str(Path(movement_primitives.__file__).parent / "dmp")]
        sys.modules["movement_primitives.dmp"] = package
        module = importlib.import_module("movement_primitives.dmp._dmp")
        return module.DMP, "movement_primitives.dmp._dmp (pytransform3d missing)"


def machine(their_import: str, **extra: str) -> dict:
    """The run's machine and library versions, for the JSON report (both DMP benchmarks)."""
    import movement_primitives

    return {
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "movement_primitives": getattr(movement_primitives, "__version__", "?"),
        "movement_primitives_import": their_import,
        **extra,
        "processor": platform.processor() or platform.machine(),
        "load_avg_at_end": [round(x, 2) for x in os.getloadavg()],
    }


def rmse(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum((a - b) ** 2, axis=1))))


def run_ours(points: np.ndarray, n_basis: int) -> tuple[float, float, float]:
    """(fit seconds, rollout seconds, RMSE cm)."""
    t0 = time.perf_counter()
    dmp = fit_dmp(points, tau=1.0, n_basis=n_basis)
    t1 = time.perf_counter()
    out = rollout(dmp)
    t2 = time.perf_counter()
    return t1 - t0, t2 - t1, rmse(out, points)


def run_theirs(their_dmp: type, points: np.ndarray, n_basis: int) -> tuple[float, float, float]:
    """(fit seconds, rollout seconds, RMSE cm); construction is counted in the fit."""
    n = len(points)
    times = np.linspace(0.0, 1.0, n)
    t0 = time.perf_counter()
    dmp = their_dmp(n_dims=2, execution_time=1.0, dt=1.0 / (n - 1), n_weights_per_dim=n_basis)
    dmp.imitate(times, points)
    t1 = time.perf_counter()
    grid, out = dmp.open_loop()
    t2 = time.perf_counter()
    if len(out) < n or not np.allclose(grid[:n], times):
        raise RuntimeError(f"movement_primitives rolled out {len(out)} samples on another grid")
    return t1 - t0, t2 - t1, rmse(out[:n], points)


def equal_error_row(their_dmp: type, n: int, rows: list[dict], args) -> dict:
    """Our fewest basis functions (of ``args.search``) whose RMSE is at most theirs at their
    largest basis count, timed (median of ``args.reps``) against that run of theirs."""
    theirs = max((r for r in rows if r["points"] == n), key=lambda r: r["basis"])
    points = word_like(n, loops=round(12 * n / 1000))
    for n_basis in sorted(args.search):
        if run_ours(points, n_basis)[2] <= theirs["theirs_rmse_cm"]:
            break
    times = [sum(run_ours(points, n_basis)[:2]) for _ in range(args.reps)]
    ours_ms = 1000 * statistics.median(times)
    theirs_ms = theirs["theirs_fit_ms"] + theirs["theirs_rollout_ms"]
    return {
        "points": n,
        "theirs_basis": theirs["basis"],
        "theirs_rmse_cm": theirs["theirs_rmse_cm"],
        "theirs_ms": round(theirs_ms, 3),
        "ours_basis": n_basis,
        "ours_rmse_cm": float(f"{run_ours(points, n_basis)[2]:.3g}"),
        "ours_ms": round(ours_ms, 3),
        "ratio": round(theirs_ms / ours_ms, 1),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", nargs="+", type=int, default=[500, 1000, 2000])
    parser.add_argument("--basis", nargs="+", type=int, default=[50, 100, 300])
    parser.add_argument("--reps", type=int, default=5, help="alternating runs per side")
    parser.add_argument("--threads", type=int, default=1, help="BLAS threads, both sides")
    parser.add_argument(
        "--search",
        nargs="+",
        type=int,
        default=[20, 30, 40, 50, 60, 75, 100, 150, 200, 300],
        help="our basis counts tried for the equal-error table",
    )
    args = parser.parse_args()

    their_dmp, their_import = load_their_dmp()
    rows = []
    with threadpool_limits(limits=args.threads):
        # one untimed run of each side first: imports, caches, BLAS start-up
        warm = word_like(200, loops=3)
        run_ours(warm, 20)
        run_theirs(their_dmp, warm, 20)
        for n in args.points:
            points = word_like(n, loops=round(12 * n / 1000))
            for n_basis in args.basis:
                ours, theirs = [], []
                for _ in range(args.reps):
                    ours.append(run_ours(points, n_basis))
                    theirs.append(run_theirs(their_dmp, points, n_basis))
                ours_fit = statistics.median(r[0] for r in ours)
                ours_roll = statistics.median(r[1] for r in ours)
                theirs_fit = statistics.median(r[0] for r in theirs)
                theirs_roll = statistics.median(r[1] for r in theirs)
                row = {
                    "points": n,
                    "basis": n_basis,
                    "ours_fit_ms": round(1000 * ours_fit, 3),
                    "theirs_fit_ms": round(1000 * theirs_fit, 3),
                    "fit_ratio": round(theirs_fit / ours_fit, 1),
                    "ours_rollout_ms": round(1000 * ours_roll, 3),
                    "theirs_rollout_ms": round(1000 * theirs_roll, 3),
                    "rollout_ratio": round(theirs_roll / ours_roll, 1),
                    "total_ratio": round((theirs_fit + theirs_roll) / (ours_fit + ours_roll), 1),
                    "ours_rmse_cm": float(f"{ours[0][2]:.3g}"),
                    "theirs_rmse_cm": float(f"{theirs[0][2]:.3g}"),
                    "ours_fit_ms_all": [round(1000 * r[0], 3) for r in ours],
                    "theirs_fit_ms_all": [round(1000 * r[0], 3) for r in theirs],
                    "ours_rollout_ms_all": [round(1000 * r[1], 3) for r in ours],
                    "theirs_rollout_ms_all": [round(1000 * r[1], 3) for r in theirs],
                }
                rows.append(row)
                print(
                    f"{n} points, {n_basis} basis: fit {row['ours_fit_ms']:.2f} vs "
                    f"{row['theirs_fit_ms']:.1f} ms, rollout {row['ours_rollout_ms']:.2f} vs "
                    f"{row['theirs_rollout_ms']:.1f} ms",
                    flush=True,
                )

        equal_error = [equal_error_row(their_dmp, n, rows, args) for n in args.points]

    report = {
        "machine": machine(their_import),
        "settings": {
            "reps": args.reps,
            "threads": args.threads,
            "order": "alternating ours, theirs; medians compared",
            "signal": "word_like: 20 x 4 cm, 12 loops per 1000 points, tau = 1, at rest at both ends",
            "ours": "fit_dmp(points, tau=1, n_basis=N), rollout(dmp)",
            "theirs": "DMP(2, execution_time=1, dt=1/(n-1), n_weights_per_dim=N).imitate(T, Y); "
            "open_loop() (rk4-cython)",
            "target_ratio": TARGET,
        },
        "rows": rows,
        "equal_error": equal_error,
    }
    print(
        f"\nDMP fit and rollout, median of {args.reps} alternating runs, {args.threads} BLAS "
        f"thread(s); ratio = theirs / ours; RMSE in cm against the demonstration"
    )
    header = (
        f"{'points':>6}{'basis':>6} | {'fit ours':>9}{'theirs':>9}{'ratio':>7} | "
        f"{'roll ours':>9}{'theirs':>9}{'ratio':>7} | {'total':>6} | {'RMSE ours':>10}{'theirs':>9}"
    )
    print(header)
    print("-" * len(header))
    for r in rows:
        flag = ""
        if r["total_ratio"] < TARGET or r["ours_rmse_cm"] > r["theirs_rmse_cm"]:
            flag = "  < target"
        print(
            f"{r['points']:>6}{r['basis']:>6} | {r['ours_fit_ms']:>7.2f}ms{r['theirs_fit_ms']:>7.1f}ms"
            f"{r['fit_ratio']:>7.1f} | {r['ours_rollout_ms']:>7.2f}ms{r['theirs_rollout_ms']:>7.1f}ms"
            f"{r['rollout_ratio']:>7.1f} | {r['total_ratio']:>6.1f} | "
            f"{r['ours_rmse_cm']:>10.2g}{r['theirs_rmse_cm']:>9.2g}{flag}"
        )
    print("\nAt equal error: our fewest basis functions reaching their RMSE at their most")
    header = (
        f"{'points':>6} | {'theirs basis':>12}{'RMSE':>8}{'fit+roll':>10} | "
        f"{'ours basis':>10}{'RMSE':>9}{'fit+roll':>10} | {'ratio':>6}"
    )
    print(header)
    print("-" * len(header))
    for r in equal_error:
        print(
            f"{r['points']:>6} | {r['theirs_basis']:>12}{r['theirs_rmse_cm']:>8.2g}"
            f"{r['theirs_ms']:>8.1f}ms | {r['ours_basis']:>10}{r['ours_rmse_cm']:>9.2g}"
            f"{r['ours_ms']:>8.2f}ms | {r['ratio']:>6.1f}"
        )
    RESULTS.mkdir(exist_ok=True)
    out = RESULTS / "bench_dmp.json"
    write_json(out, report)
    print(f"\nwrote {out}")


if __name__ == "__main__":
    main()
