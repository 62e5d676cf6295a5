"""Benchmark the importance-weighted log-likelihood estimator against the raw decoder.

Throughput: for a MUSE model (the paper's networks, seeded random weights: speed does not depend
on the weights) and one batch of test-shaped inputs, ``estimate_cell`` (proposal sampling,
decoding, likelihood, prior and proposal densities, running log-sum-exp) is timed against a
plain loop that only pushes the same number of latent samples, in the same chunk sizes, through
the same decoder (``torch.no_grad``). Ratio = estimator samples/s / decoder samples/s (target
>= 0.8). Cells: the image conditional log p(x_I | x_T) (image decoder, the slow one) and the
trajectory conditional log p(x_T | x_S). The two sides alternate ``--reps`` times; medians are
compared.

Memory (Linux): each configuration runs in a fresh subprocess that reports its peak resident
memory (``VmHWM``, reset just before) above the memory it held before estimating: K = 5000 for the image and
trajectory conditionals at several ``chunk_rows`` (the bound: decoder outputs alive at once),
and, as the reference, the unchunked estimate (all K samples at once) of the trajectory cell.
The memory runs use a batch of ``MEMORY_BATCH`` test samples to keep the image runs short; the
peak depends on ``chunk_rows``, not on K or the batch.

Usage: ``python benchmarks/bench_evaluate.py [--reps 3] [--k-image 250] [--k-traj 2000]``
Prints a table and writes ``benchmarks/results/bench_evaluate.json``.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

import torch

from prg.evaluation.likelihood import estimate_cell
from prg.files import write_json
from prg.models.muse import MUSE

RESULTS = Path(__file__).parent / "results"
TARGET = 0.8
BATCH = 64
MEMORY_BATCH = 8
CELLS = {"image_given_traj": ("image", ("traj",)), "traj_given_label": ("traj", ("label",))}


def make_model_and_data(batch: int = BATCH):
    torch.manual_seed(0)
    model = MUSE().eval()
    data = {
        "traj": torch.randn(batch, 200) * 0.3,
        "label": torch.randint(0, 62, (batch,)),
        "image": torch.rand(batch, 1, 28, 28),
    }
    return model, data


@torch.no_grad()
def decoder_only(model, target, given, data, k, chunk_rows) -> None:
    """The reference: the same latent count through the same decoder, nothing else."""
    posterior = model.encode({m: data[m] for m in given})
    batch = len(data[target])
    chunk = max(1, chunk_rows // batch)
    done = 0
    while done < k:
        n = min(chunk, k - done)
        z = posterior.mu.expand(n, *posterior.mu.shape).reshape(n * batch, -1)
        model.decode(z, target)
        done += n


def throughput(model, data, cell, k, chunk_rows, reps):
    target, given = CELLS[cell]
    samples = k * len(data[target])
    times = {"estimator": [], "decoder": []}
    for _ in range(reps):
        start = time.perf_counter()
        estimate_cell(model, target, given, data, k, BATCH, chunk_rows)
        times["estimator"].append(time.perf_counter() - start)
        start = time.perf_counter()
        decoder_only(model, target, given, data, k, chunk_rows)
        times["decoder"].append(time.perf_counter() - start)
    rates = {side: samples / statistics.median(t) for side, t in times.items()}
    return {
        "cell": cell,
        "k": k,
        "batch": BATCH,
        "chunk_rows": chunk_rows,
        "estimator_samples_per_s": round(rates["estimator"]),
        "decoder_samples_per_s": round(rates["decoder"]),
        "ratio": round(rates["estimator"] / rates["decoder"], 3),
    }


def _vm_kib(field: str) -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1])
    raise RuntimeError(f"{field} not in /proc/self/status")


def _peak_child(cell: str, k: int, chunk_rows: int) -> None:
    """Runs in a subprocess: print the peak RSS increase (MiB) of one estimate.

    The kernel's peak-RSS mark is reset just before the estimate (``5`` to
    ``/proc/self/clear_refs``), so set-up peaks (imports, model construction) do not hide it.
    """
    model, data = make_model_and_data(MEMORY_BATCH)
    target, given = CELLS[cell]
    estimate_cell(model, target, given, data, 1, MEMORY_BATCH, chunk_rows)  # warm up allocators
    Path("/proc/self/clear_refs").write_text("5")
    before = _vm_kib("VmRSS")
    estimate_cell(model, target, given, data, k, MEMORY_BATCH, chunk_rows)
    peak = _vm_kib("VmHWM")
    print(
        json.dumps({"peak_mib": round((peak - before) / 1024, 1), "rss_before_mib": before // 1024})
    )


def peak_memory(cell: str, k: int, chunk_rows: int) -> dict:
    out = subprocess.run(
        [sys.executable, __file__, "--child", cell, str(k), str(chunk_rows)],
        capture_output=True,
        text=True,
        check=True,
    )
    result = json.loads(out.stdout.strip().splitlines()[-1])
    return {"cell": cell, "k": k, "batch": MEMORY_BATCH, "chunk_rows": chunk_rows, **result}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--reps", type=int, default=3)
    parser.add_argument("--k-image", type=int, default=250)
    parser.add_argument("--k-traj", type=int, default=2000)
    parser.add_argument("--chunk-rows", type=int, default=4096)
    parser.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        _peak_child(args.child[0], int(args.child[1]), int(args.child[2]))
        return

    model, data = make_model_and_data()
    rows = [
        throughput(model, data, "image_given_traj", args.k_image, args.chunk_rows, args.reps),
        throughput(model, data, "traj_given_label", args.k_traj, args.chunk_rows, args.reps),
    ]
    print(f"{'cell':18} {'K':>5} {'estimator/s':>12} {'decoder/s':>10} {'ratio':>6}")
    for r in rows:
        print(
            f"{r['cell']:18} {r['k']:5d} {r['estimator_samples_per_s']:12d} "
            f"{r['decoder_samples_per_s']:10d} {r['ratio']:6.3f}"
        )

    memory = []
    for cell, chunks in (
        ("image_given_traj", (1024, 4096, 16384)),
        ("traj_given_label", (1024, 4096, 16384, 5000 * MEMORY_BATCH)),
    ):
        for chunk_rows in chunks:
            memory.append(peak_memory(cell, 5000, chunk_rows))
    print(f"\npeak memory above the loaded model, K = 5000, batch {MEMORY_BATCH}")
    print(f"{'cell':18} {'chunk_rows':>10} {'peak MiB':>9}")
    for m in memory:
        label = "all" if m["chunk_rows"] >= 5000 * MEMORY_BATCH else str(m["chunk_rows"])
        print(f"{m['cell']:18} {label:>10} {m['peak_mib']:9.1f}")

    RESULTS.mkdir(exist_ok=True)
    payload = {
        "benchmark": "bench_evaluate",
        "reference": "raw decoder forward on the same number of latent samples (same run)",
        "target_ratio": TARGET,
        "machine": {
            "platform": platform.platform(),
            "torch": torch.__version__,
            "threads": torch.get_num_threads(),
        },
        "throughput": rows,
        "peak_memory_k5000": memory,
    }
    path = RESULTS / "bench_evaluate.json"
    write_json(path, payload)
    print(f"\nwrote {path}")


if __name__ == "__main__":
    main()
