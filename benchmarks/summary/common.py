"""What every part of the summary shares: where things are, the error it raises, JSON reading,
Markdown cells and the benchmark row."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

from prg.evaluation.reports import _md_table

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "benchmarks" / "results"
DEMO = RESULTS / "demo"
CONVERGED = RESULTS / "converged"
BASELINES = RESULTS / "baselines"

table = _md_table  # header and rows -> a Markdown table, as prg.evaluation.reports writes them


class SummaryError(Exception):
    """A results file that is missing or does not have the expected fields."""


@dataclass(frozen=True)
class Row:
    """One benchmark figure: ours beside the reference measured in the same run."""

    figure: str
    ours: str
    reference: str
    reference_value: str
    ratio: float  # ours / reference
    target: str = ""


def read_json(path: Path) -> dict:
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise SummaryError(f"{path}: missing (run its benchmark or `make demo`)") from None
    except (OSError, ValueError) as err:
        raise SummaryError(f"{path}: not readable JSON ({err})") from None


def number(metrics: dict, key: str, fmt: str) -> str:
    """A metric formatted, or '-' when the snapshot does not hold it."""
    value = metrics.get(key)
    return "-" if value is None else format(value, fmt)


def ratio_text(value: float) -> str:
    """A ratio in a table cell: 3 significant digits, '-' for none (NaN)."""
    if math.isnan(value):
        return "-"
    if not math.isfinite(value):
        return str(value)
    if value == 0 or 0.01 <= abs(value) < 1000:
        return f"{value:.3g}"
    return f"{value:.1e}"
