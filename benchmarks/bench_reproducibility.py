"""How far one model's reported metrics move when its training runs again elsewhere, against the
spread its seeds give.

Two evaluations of the same (family, seed), trained twice (e.g. on a CPU with AVX-512 and one
held to AVX2), are compared metric by metric: every metric of the baselines' tables
(:data:`prg.evaluation.seeds.TABLES`, times left out), as the absolute difference and as a ratio
to the reference, the standard deviation of that metric over the family's seeds in a sweep
(``make baselines``; the committed snapshot by default). A ratio under 1 is a move smaller than
retraining with another seed gives.

Usage::

    python benchmarks/bench_reproducibility.py RUN_A RUN_B [--family cvae] [--seed S]
        [--seeds benchmarks/results/baselines/seeds]

``RUN_A`` and ``RUN_B`` are sweep-shaped folders (``seed<s>/reports/<family>/metrics.json``,
as :mod:`prg.commands.baselines` evaluates them); the seed compared is the one both have, or
``--seed``. Prints a table and
writes ``benchmarks/results/bench_reproducibility.json``.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"


def reported(metric: str) -> bool:
    """A metric of the baselines' tables, times left out."""
    from prg.evaluation.seeds import table_of

    return any(t != "timing" for t in table_of(metric))


def compare(a: dict, b: dict, spread: dict) -> list[dict]:
    """One row per reported metric both runs have: values, |difference|, seeds' sd, ratio."""
    from prg.evaluation.seeds import summarise

    rows = []
    for metric in sorted(set(a) & set(b)):
        if not reported(metric):
            continue
        by_seed = spread.get(metric, {})
        sd = summarise(by_seed)["sd"] if by_seed else math.nan  # NaN for one seed
        diff = abs(a[metric] - b[metric])
        if math.isnan(sd):  # one seed: no spread to compare with
            ratio = math.nan
        else:
            ratio = diff / sd if sd > 0 else (0.0 if diff == 0 else math.inf)
        rows.append(
            {
                "metric": metric,
                "a": a[metric],
                "b": b[metric],
                "diff": diff,
                "sd": sd,
                "seeds": len(by_seed),
                "ratio": ratio,
            }
        )
    return rows


def summary(rows: list[dict]) -> dict:
    ratios = [r["ratio"] for r in rows if not math.isnan(r["ratio"])]
    return {
        "metrics": len(rows),
        "with_seed_sd": len(ratios),
        "within_1_sd": sum(r <= 1 for r in ratios),
        "within_2_sd": sum(r <= 2 for r in ratios),
        "median_ratio": statistics.median(ratios) if ratios else math.nan,
        "max_ratio": max(ratios) if ratios else math.nan,
        "largest": sorted(rows, key=lambda r: -r["ratio"] if not math.isnan(r["ratio"]) else 0)[
            :10
        ],
    }


def main(argv: list[str] | None = None) -> int:
    from prg.evaluation.seeds import collect, json_ready
    from prg.files import write_json
    from prg.resources import project_path

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run_a", type=Path)
    parser.add_argument("run_b", type=Path)
    parser.add_argument("--family", default="cvae")
    parser.add_argument("--seed", type=int, help="the seed to compare (default: the one both have)")
    parser.add_argument("--label", default="run B", help="what run B is, for the summary table")
    parser.add_argument("--seeds", type=Path, default=RESULTS / "baselines" / "seeds")
    args = parser.parse_args(argv)
    from prg.errors import UsageError

    try:
        runs = [collect(run, [args.family]) for run in (args.run_a, args.run_b)]
        reference = collect(args.seeds, [args.family])
    except UsageError as err:
        print(f"bench_reproducibility: {err}", file=sys.stderr)
        return 2
    seeds_a, seeds_b = (set(next(iter(r[args.family].values()))) for r in runs)
    common = sorted(seeds_a & seeds_b) if args.seed is None else [args.seed]
    if len(common) != 1 or not {common[0]} <= seeds_a & seeds_b:
        print(
            f"bench_reproducibility: the runs have seeds {sorted(seeds_a)} and {sorted(seeds_b)}: "
            "give --seed, one seed both have",
            file=sys.stderr,
        )
        return 2
    seed_a = common[0]
    a, b = ({m: v[seed_a] for m, v in r[args.family].items() if seed_a in v} for r in runs)
    rows = compare(a, b, reference[args.family])
    result = {
        "family": args.family,
        "seed": seed_a,
        "label": args.label,
        "run_a": project_path(args.run_a, ROOT),
        "run_b": project_path(args.run_b, ROOT),
        "seeds": project_path(args.seeds, ROOT),
        **summary(rows),
    }
    print(
        f"{args.family} seed {seed_a}: {len(rows)} reported metrics, |A - B| against the sd "
        f"over {args.family}'s seeds in {result['seeds']}"
    )
    print(f"{'metric':55s} {'A':>9s} {'B':>9s} {'|A-B|':>8s} {'seeds sd':>9s} {'ratio':>6s}")
    for r in result["largest"]:
        print(
            f"{r['metric']:55s} {r['a']:9.4f} {r['b']:9.4f} {r['diff']:8.4f} {r['sd']:9.4f} "
            f"{r['ratio']:6.2f}"
        )
    print(
        f"within 1 sd: {result['within_1_sd']} of {result['with_seed_sd']}; within 2 sd: "
        f"{result['within_2_sd']}; median ratio {result['median_ratio']:.2f}, "
        f"max {result['max_ratio']:.2f}"
    )
    write_json(RESULTS / "bench_reproducibility.json", json_ready(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
