"""The baselines' section (``make baselines``: families x seeds of the quick profile, every table
as mean and 95 % CI over seeds with paired, Holm-corrected comparisons), from the snapshot of its
``aggregate.json`` in ``benchmarks/results/baselines/`` (``--snapshot-baselines baselines``).

The snapshot keeps the per-(seed, family) metrics too (``seeds/``, the sweep's own layout: a
few kB each), so a later run that adds families or seeds can be aggregated with these without
retraining them: copy ``seeds/`` into the sweep's folder, then ``python -m
prg.commands.baselines aggregate``."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from prg.evaluation.seed_report import seeds_text, summary_markdown, summary_only
from prg.files import write_bytes

from .common import BASELINES, SummaryError, read_json

AGGREGATE = "aggregate.json"


def baselines_markdown(baselines: Path = BASELINES) -> str:
    """The short tables over seeds (cross-modal coherence, roughness, Table I conditionals,
    times) and the sweep's wall time, or a line saying how to get them."""
    if not (baselines / AGGREGATE).is_file():
        return (
            "No baselines snapshot yet: `make baselines`, then "
            "`python benchmarks/summarize.py --snapshot-baselines baselines`."
        )
    agg = read_json(baselines / AGGREGATE)
    starts = agg.get("starts", 1)
    wall = (
        f"{agg['wall_min']:.1f} min wall on {agg.get('machine', 'this machine')}"
        + (f" (summed over {starts} starts: stopped and run again)" if starts > 1 else "")
        if agg.get("wall_min") is not None
        else "wall time not recorded"
    )
    families = [f for f in agg["families"] if f != "real"]
    counts = {
        len(max((row["seeds"] for row in agg["summaries"][f].values()), key=len, default=[]))
        for f in families
    }
    uneven = " (not every family on each: each table's Seeds line says which)"
    head = (
        f"`make baselines`: {', '.join(f'`{f}`' for f in families)} x "
        f"seeds {seeds_text(agg['seeds'])}{uneven if len(counts) > 1 else ''} (quick profile), "
        f"{wall}. Every table of the run, each pairwise comparison and the figure are in "
        "`baselines/report/`."
    )
    return head + "\n\n" + summary_markdown(agg, heading="###").rstrip("\n")


#: What the snapshot keeps of each (seed, family), relative to the sweep's folder.
PER_SEED = (
    "seed{seed}/{family}/metrics.json",  # training: fit times, epochs
    "seed{seed}/reports/{family}/metrics.json",  # evaluation: every table's values
    "seed{seed}/reports/{family}/timing.json",  # evaluation: CPU and wall time
)


def snapshot_baselines(source: Path, baselines: Path = BASELINES) -> None:
    """Copy ``<source>/report/aggregate.json`` of a finished ``make baselines`` into
    ``baselines``, cut down to what the docs show (:func:`prg.evaluation.seed_report.summary_only`),
    and the per-(seed, family) metrics it was aggregated from (every evaluated pair) into
    ``baselines/seeds/`` (replacing an older snapshot's)."""
    path = source / "report" / AGGREGATE
    agg = read_json(path)
    if not agg.get("summaries") or not agg.get("seeds"):
        raise SummaryError(f"{path}: not an aggregate of a baselines sweep")
    families = [f for f in agg["families"] if f != "real"]
    # the (seed, family) pairs evaluated: a family may have fewer seeds than the sweep
    pairs = [
        (seed, family)
        for seed in agg["seeds"]
        for family in families
        if (source / PER_SEED[1].format(seed=seed, family=family)).is_file()
    ]
    files = [p.format(seed=seed, family=family) for seed, family in pairs for p in PER_SEED]
    missing = [f for f in files if not (source / f).is_file()]
    missing += [
        PER_SEED[1].format(seed=agg["seeds"][0], family=f)
        for f in families
        if f not in {family for _, family in pairs}
    ]
    if missing:
        raise SummaryError(f"{source / missing[0]} does not exist: the aggregate's own inputs")
    baselines.mkdir(parents=True, exist_ok=True)
    shutil.rmtree(baselines / "seeds", ignore_errors=True)
    for name in files:
        (baselines / "seeds" / name).parent.mkdir(parents=True, exist_ok=True)
        write_bytes(baselines / "seeds" / name, (source / name).read_bytes())
    # what the docs show (the whole aggregate is regenerated from seeds/ when wanted): the
    # whole one, every metric compared between 7 families, is over 1 MB
    slim = json.dumps(summary_only(agg), separators=(",", ":")) + "\n"
    write_bytes(baselines / AGGREGATE, slim.encode())
