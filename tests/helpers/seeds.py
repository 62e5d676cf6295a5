"""A sweep's folders of per-seed metrics, written for the tests of the results over seeds."""

from __future__ import annotations

from prg.evaluation import seeds
from prg.files import write_json


def seed_sweep(root, families=("cvae", "avae_ts"), seed_ids=(0, 1, 2)):
    for s in seed_ids:
        for i, f in enumerate(families):
            write_json(
                root / f"seed{s}" / f / "metrics.json",
                {"family": f, "fit_cpu_s": 120.0 + s, "fit_wall_s": 60.0, "epochs": 1},
            )
            where = seeds.evaluation_dir(root, s, f)
            write_json(
                where / "metrics.json",
                {
                    f"{f}/coherence_T_given_S": 0.5 + 0.1 * i + 0.01 * s * (i + 1),
                    f"{f}/roughness_ratio_T_given_S": 1.2 + 0.1 * s,
                    "real/likeness_val_writers_legible": 0.9,
                    "classifier/traj/test_accuracy": 0.92,
                },
            )
            write_json(where / "timing.json", {"cpu_s": 30.0, "wall_s": 20.0})
    return root
