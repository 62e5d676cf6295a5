"""One results table from the benchmark and demo-report JSON: ``benchmarks/results.md`` and the
generated blocks of ``docs/results.md`` (demo, converged) and ``docs/benchmarks.md``
(benchmarks); numbers are never typed by hand.

    python benchmarks/summarize.py              # results.md + docs blocks from the committed JSON
    python benchmarks/summarize.py --snapshot   # first copy the demo's report JSON (after `make demo`)
                                                # into benchmarks/results/demo/
    python benchmarks/summarize.py --snapshot-converged converged   # after `make converged`
    python benchmarks/summarize.py --snapshot-baselines baselines   # after `make baselines`
    python benchmarks/summarize.py --check      # exit 1 if results.md or a docs page is stale

Inputs: ``benchmarks/results/bench_*.json`` (written by each benchmark) and
``benchmarks/results/demo/*.json`` (a snapshot of the DVC pipeline's metrics, with the
``dvc.lock`` hashes of the outputs they came from). Every benchmark figure is shown next to the
reference it was measured against in the same run, with the ratio ours / reference.

The work is done by the package ``benchmarks/summary/``; this file is its entry point and keeps
its names at hand for the tests.
"""

from __future__ import annotations

import sys
from pathlib import Path

_HERE = str(Path(__file__).resolve().parent)
if _HERE not in sys.path:  # loaded by path (the tests) rather than run as a script
    sys.path.insert(0, _HERE)

from summary.baselines import baselines_markdown, snapshot_baselines  # noqa: E402
from summary.bench_table import BENCHMARKS, benchmark_rows, benchmarks_markdown  # noqa: E402
from summary.common import (  # noqa: E402
    CONVERGED,
    DEMO,
    RESULTS,
    ROOT,
    Row,
    SummaryError,
    ratio_text,
)
from summary.outputs import (  # noqa: E402
    BLOCKS,
    SUMMARY,
    docs_texts,
    fill_block,
    main,
    results_markdown,
)
from summary.reports import converged_markdown, demo_markdown  # noqa: E402
from summary.snapshot import (  # noqa: E402
    CONVERGED_SOURCES,
    DEMO_SOURCES,
    snapshot,
    snapshot_converged,
)

__all__ = [
    "BENCHMARKS",
    "BLOCKS",
    "CONVERGED",
    "CONVERGED_SOURCES",
    "DEMO",
    "DEMO_SOURCES",
    "RESULTS",
    "ROOT",
    "SUMMARY",
    "Row",
    "SummaryError",
    "baselines_markdown",
    "benchmark_rows",
    "benchmarks_markdown",
    "converged_markdown",
    "demo_markdown",
    "docs_texts",
    "fill_block",
    "main",
    "ratio_text",
    "results_markdown",
    "snapshot",
    "snapshot_baselines",
    "snapshot_converged",
]

if __name__ == "__main__":
    sys.exit(main())
