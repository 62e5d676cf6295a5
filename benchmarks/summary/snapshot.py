"""Snapshots of the pipelines' metrics JSON: the demo's (``--snapshot``, after ``make demo``,
with the ``dvc.lock`` hash of each output) and the converged profile's (``--snapshot-converged``,
after ``make converged``), copied under ``benchmarks/results/``."""

from __future__ import annotations

from pathlib import Path

from prg.checks import PAPER_FAMILIES
from prg.files import write_bytes, write_json

from .common import CONVERGED, DEMO, ROOT, SummaryError, read_json

# each model's and the classifiers' metrics, relative to the folder that holds ``models/``
PIPELINE_FAMILIES = PAPER_FAMILIES  # dvc.yaml's train matrix and make converged's families
MODEL_SOURCES = {
    **{f"models_{f}.json": f"models/{f}/metrics.json" for f in PIPELINE_FAMILIES},
    "classifiers.json": "models/classifiers/metrics.json",
    "evaluate.json": "reports/metrics.json",
}
# DVC outputs copied by --snapshot: snapshot name -> path in the repository after `make demo`
DEMO_SOURCES = {
    "prepare.json": "reports/prepare/synthetic/metrics.json",
    **MODEL_SOURCES,
    "dictaphone.json": "reports/dictaphone/metrics.json",
    "simulate.json": "reports/simulate/metrics.json",
    "study.json": "reports/study/readability/metrics.json",
}
# outputs of `make converged` copied by --snapshot-converged: snapshot name -> path under its root
CONVERGED_SOURCES = {**MODEL_SOURCES, "run.json": "reports/paper_scale.json"}


def _copy_json(source: Path, target: Path) -> None:
    """Copy a JSON file that reads as JSON, all or nothing."""
    read_json(source)
    write_bytes(target, source.read_bytes())


def snapshot(root: Path = ROOT, demo: Path = DEMO) -> None:
    """Copy the demo pipeline's metrics JSON into ``demo`` with their ``dvc.lock`` hashes."""
    import yaml

    lock = yaml.safe_load((root / "dvc.lock").read_text())
    hashes = {
        out["path"]: out.get("md5", "")
        for stage in lock["stages"].values()
        for out in stage.get("outs", [])
    }
    demo.mkdir(parents=True, exist_ok=True)
    provenance = {}
    for name, source in DEMO_SOURCES.items():
        _copy_json(root / source, demo / name)
        # the lock entry of the file itself, or of the output folder holding it
        owner = max(
            (out for out in hashes if source == out or source.startswith(out + "/")),
            key=len,
            default=None,
        )
        provenance[name] = {"source": source, "dvc_out": owner, "dvc_md5": hashes.get(owner)}
    write_json(demo / "provenance.json", provenance)


def snapshot_converged(source: Path, converged: Path = CONVERGED) -> None:
    """Copy the metrics of a finished ``make converged`` (its ``--root``) into ``converged``."""
    run = read_json(source / CONVERGED_SOURCES["run.json"])
    if run.get("status") != "ok" or run.get("profile") != "converged":
        raise SummaryError(
            f"{source / CONVERGED_SOURCES['run.json']}: not a finished converged run "
            f"(profile {run.get('profile')!r}, status {run.get('status')!r})"
        )
    converged.mkdir(parents=True, exist_ok=True)
    for name, relative in CONVERGED_SOURCES.items():
        _copy_json(source / relative, converged / name)
