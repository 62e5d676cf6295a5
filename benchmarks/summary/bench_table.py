"""The benchmark table: every benchmark's JSON under ``benchmarks/results/`` as rows, ours beside
the reference measured in the same run, with the ratio ours / reference."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from .common import RESULTS, Row, SummaryError, ratio_text, read_json, table
from .rows_models import (
    evaluate_rows,
    prepare_rows,
    reproducibility_rows,
    startup_rows,
    train_rows,
)
from .rows_speech import speech_rows
from .rows_writing import (
    connections_rows,
    dmp_rows,
    kinematics_rows,
    lasa_rows,
    simulate_rows,
    write_rows,
)

# benchmark (its JSON's stem) -> its rows, in the order of `make bench`
BENCHMARKS: dict[str, Callable[[dict], list[Row]]] = {
    "bench_prepare": prepare_rows,
    "bench_train": train_rows,
    "bench_evaluate": evaluate_rows,
    "bench_dmp": dmp_rows,
    "bench_lasa": lasa_rows,
    "bench_write": write_rows,
    "bench_connections": connections_rows,
    "bench_kinematics": kinematics_rows,
    "bench_speech": speech_rows,
    "bench_speech_other_voices": speech_rows,
    "bench_speech_other_words": speech_rows,
    "bench_simulate": simulate_rows,
    "bench_startup": startup_rows,
    "bench_reproducibility": reproducibility_rows,
}


def benchmark_rows(results: Path = RESULTS) -> dict[str, list[Row]]:
    """Rows of every benchmark whose JSON exists, in the order of ``make bench``."""
    out = {}
    for name, adapter in BENCHMARKS.items():
        path = results / f"{name}.json"
        if not path.is_file():
            continue
        try:
            out[name] = adapter(read_json(path))
        except (KeyError, TypeError, ZeroDivisionError) as err:
            raise SummaryError(
                f"{path}: unexpected content ({type(err).__name__}: {err})"
            ) from None
    return out


def paper_cost_markdown(results: Path = RESULTS) -> str:
    """The paper profile's training time on this CPU, from bench_train's measured throughput."""
    path = results / "bench_train.json"
    if not path.is_file():
        return ""
    d = read_json(path)
    samples, threads = d["settings"]["train_samples"], d["settings"]["threads"]
    hours = ", ".join(
        f"{family} {50 * samples / f['lightning_samples_per_s'] / 3600:.1f} h"
        for family, f in d["families"].items()
    )
    return (
        f"\n\n`experiment=paper` (50 epochs over {samples:,} training samples) at the measured "
        f"Lightning throughput ({threads} torch thread, validation not counted): {hours}."
    )


def benchmarks_markdown(results: Path = RESULTS) -> str:
    """The benchmark table with its header line and the paper profile's estimated cost."""
    rows = benchmark_rows(results)
    body = [
        [name, r.figure, r.ours, r.reference, r.reference_value, ratio_text(r.ratio), r.target]
        for name, items in rows.items()
        for r in items
    ]
    header = ["benchmark", "figure", "ours", "reference", "reference value", "ratio", "target"]
    return (
        "Ratio = ours / reference, both measured in the same run (`make bench`; JSON in "
        "`benchmarks/results/`). Times: lower is better; throughput and accuracy: higher.\n\n"
        + table(header, body)
        + paper_cost_markdown(results)
    )
