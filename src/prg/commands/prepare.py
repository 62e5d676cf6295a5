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

from omegaconf import DictConfig

from prg.checks import check_values
from prg.commands.cli import check_output
from prg.data.build import BuildResult, build_dataset

log = logging.getLogger(__name__)


def prepare(cfg: DictConfig) -> BuildResult:
    """Task: build ``${paths.data_dir}/prepared/${data.name}/`` from the composed config."""
    check_values(cfg)
    check_output(cfg.paths.data_dir, "paths.data_dir")
    if cfg.get("metrics_path"):
        check_output(cfg.metrics_path, "metrics_path", folder=False)
    result = build_dataset(
        cfg.data,
        cfg.paths.data_dir,
        workers=cfg.get("workers", 2),
        progress=cfg.get("progress", True),
        figures=cfg.get("figures", True),
        metrics_path=cfg.get("metrics_path") or None,
    )
    counts = result.manifest["counts"]
    log.info(
        "wrote %s: %s",
        result.out_dir,
        ", ".join(f"{s} {c['total']} samples / {c['writers']} writers" for s, c in counts.items()),
    )
    log.info("stage timings (s): %s", json.dumps(result.timings))
    return result


if __name__ == "__main__":
    from prg.commands.entry import prepare

    prepare()
