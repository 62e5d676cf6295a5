"""Benchmark how the pen moves: the robot's writing against human motion, with the controls.

For a fixed list of words (``WORDS``), the demo MUSE writes each (its hand and seed ``i``) with
the human timing (the default) and with the paper's constant speed; for each word the planned
body (the DMP's rollout) and the simulated Panda's executed pen tip (PyBullet, the first pen-down
stroke, resampled at 100 Hz) are measured with :func:`prg.evaluation.kinematics.kinematics`:
the speed-curvature power law's beta and its R^2, the speed's coefficient of variation, speed
peaks per second, SPARC and the SNR of a sigma-lognormal fit. Beside them, measured the same
way: the LASA human handwriting demonstrations (the reference) and the estimator's controls,
white noise and a constant-speed path. Each cell is a median (p10-p90 in the JSON); the
executed pen tip's ratio to LASA is printed. Targets on the executed pen tip, human timing:
beta between 0.2 and 0.4, speed CV >= 0.25, sigma-lognormal SNR >= 20 dB.

Usage: ``python benchmarks/bench_kinematics.py`` (needs ``models/muse/model.ckpt``, ``make
demo``; the LASA set from ``prg[lasa]``). Prints a table and writes
``benchmarks/results/bench_kinematics.json``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from prg.evaluation.kinematics import MEASURES, TARGETS

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
WORDS = ("bell", "cat", "jump", "joy", "little", "letter", "water", "moon", "house", "people")
DT = 0.01


def summary(rows: list[dict]) -> dict:
    return {
        m: {
            "median": float(np.median([r[m] for r in rows])),
            "p10": float(np.percentile([r[m] for r in rows], 10)),
            "p90": float(np.percentile([r[m] for r in rows], 90)),
        }
        for m in MEASURES
    }


def main() -> int:
    from prg.evaluation.kinematics import kinematics_rows
    from prg.files import write_json
    from prg.models.checkpoint import load_model

    ckpt = ROOT / "models" / "muse" / "model.ckpt"
    if not ckpt.is_file():
        print(f"bench_kinematics: {ckpt.relative_to(ROOT)} is missing: run `make demo` first")
        return 2
    model, info = load_model(ckpt)
    groups = kinematics_rows(
        model, info["hands"], WORDS, progress=lambda line: print(line, flush=True)
    )
    n_lasa = len(groups["LASA (human)"])
    table = {name: summary(rows) for name, rows in groups.items()}
    lasa = table["LASA (human)"]
    print(
        f"\nPen kinematics, medians over {len(WORDS)} words (demo MUSE, Panda) and "
        f"{n_lasa} LASA demonstrations; ratio: executed (human timing) over LASA"
    )
    header = f"{'':>26}" + "".join(f"{m:>17}" for m in MEASURES)
    print(header)
    print("-" * len(header))
    for name, cells in table.items():
        print(f"{name:>26}" + "".join(f"{cells[m]['median']:>17.3f}" for m in MEASURES))
    executed = table["human: executed"]
    ratios = {m: executed[m]["median"] / lasa[m]["median"] for m in MEASURES}
    print(f"{'ratio to LASA':>26}" + "".join(f"{ratios[m]:>17.2f}" for m in MEASURES))
    verdicts = {}
    for m, (low, high) in TARGETS.items():
        value = executed[m]["median"]
        verdicts[m] = (low is None or value >= low) and (high is None or value <= high)
        print(f"target {m}: {value:.3f} in [{low}, {high}]: {'met' if verdicts[m] else 'NOT met'}")
    RESULTS.mkdir(exist_ok=True)
    out = RESULTS / "bench_kinematics.json"
    write_json(
        out,
        {
            "settings": {"words": list(WORDS), "dt": DT, "targets": TARGETS},
            "table": table,
            "ratios_to_lasa": ratios,
            "targets_met": verdicts,
        },
    )
    print(f"\nwrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
