"""``prg-prepare``: build the handwriting dataset (synthetic by default, or UJI).

Examples
--------
``prg-prepare``                                   synthetic set, ``data/prepared/synthetic/``
``prg-prepare data=uji data.uji_path=FILE``       the real UJI Pen Characters v2 file (.txt or .zip)
``prg-prepare data.augment.per_class=200 paths.data_dir=/tmp/d``
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

from omegaconf import DictConfig

from prg.cli import check_output, hydra_command
from prg.data.build import BuildResult, build_dataset, dataset_metrics, write_json

log = logging.getLogger(__name__)


def prepare(cfg: DictConfig) -> BuildResult:
    """Task: build ``${paths.data_dir}/prepared/${data.name}/`` from the composed config."""
    check_output(cfg.paths.data_dir, "paths.data_dir")
    if cfg.get("metrics_path"):
        check_output(cfg.metrics_path, "metrics_path", folder=False)
    result = build_dataset(
        cfg.data,
        cfg.paths.data_dir,
        workers=cfg.get("workers", 2),
        progress=cfg.get("progress", True),
        figures=cfg.get("figures", True),
    )
    counts = result.manifest["counts"]
    log.info(
        "wrote %s: %s",
        result.out_dir,
        ", ".join(f"{s} {c['total']} samples / {c['writers']} writers" for s, c in counts.items()),
    )
    log.info("stage timings (s): %s", json.dumps(result.timings))
    if cfg.get("metrics_path"):
        Path(cfg.metrics_path).parent.mkdir(parents=True, exist_ok=True)
        write_json(cfg.metrics_path, dataset_metrics(result.manifest))
    return result


main = hydra_command(prepare, "prepare", "prg-prepare")

if __name__ == "__main__":
    main()
