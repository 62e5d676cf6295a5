"""Tests of ``prg.evaluation.seed_report``: cells with and without an interval, the reports and
the figure written whole (and a failing figure leaving the previous one), the summary of both
classifiers' cells, the summary-only aggregate."""

from __future__ import annotations

import json
import os

import pytest

from prg.evaluation import seed_report, seeds
from tests.helpers.seeds import seed_sweep


def test_cell_text_blank_mean_alone_and_interval():
    assert seed_report.cell_text(None, ".3f") == ""
    assert seed_report.cell_text({"mean": 0.5, "ci_low": None, "ci_high": None}, ".3f") == "0.500"
    assert seed_report.cell_text({"mean": 0.5, "ci_low": 0.4, "ci_high": 0.6}, ".2f") == (
        "0.50 [0.40, 0.60]"
    )


def test_reports_and_figure_are_written_whole(tmp_path, monkeypatch):
    agg = seeds.aggregate(seeds.collect(seed_sweep(tmp_path / "b")))
    texts = seed_report.report_texts(agg, "took 1 min")
    assert {"coherence.md", "table1.csv", "comparisons.csv", "index.md", "aggregate.json"} <= set(
        texts
    )
    loaded = json.loads(texts["aggregate.json"])
    assert loaded["summaries"]["cvae"]["coherence_T_given_S"]["n"] == 3
    assert "real letters" in texts["likeness.md"]
    assert "coherence_T_given_S,cvae,avae_ts,3," in texts["comparisons.csv"]
    # the figure goes to a temporary name first, then is renamed over the final one
    renames = []
    real_replace = os.replace
    monkeypatch.setattr(os, "replace", lambda a, b: (renames.append((a, b)), real_replace(a, b)))
    path = seed_report.comparison_figure(agg, tmp_path / "comparison.png")
    assert path.read_bytes()[:4] == b"\x89PNG"
    ((tmp, final),) = renames
    assert final == path and tmp.name.startswith(".comparison.tmp-")
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_a_failing_figure_leaves_the_previous_one(tmp_path, monkeypatch):
    agg = seeds.aggregate(seeds.collect(seed_sweep(tmp_path / "b")))
    path = tmp_path / "comparison.png"
    path.write_bytes(b"old")
    import matplotlib.figure

    def broken(self, *args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", broken)
    with pytest.raises(OSError):
        seed_report.comparison_figure(agg, path)
    assert path.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_the_summary_and_figure_show_both_classifiers_folded_cross_modal_cells(tmp_path):
    metrics = [
        "coherence_folded_T_given_S",
        "coherence_folded_second_T_given_S",
        "coherence_folded_second_T_given_T",  # a reconstruction: not cross-modal
        "coherence_folded_sampled_T_given_S",  # sampled: not the posterior mean
    ]
    assert seed_report.cross_modal(metrics, folded=True) == metrics[:2]
    assert seed_report.cross_modal(metrics) == []
    assert (
        seed_report._cell_label(metrics[1]) == "T|S 2nd"
        and seed_report._cell_label(metrics[0]) == "T|S"
    )
    values = {
        "cvae": {
            "coherence_T_given_S": {0: 0.84, 1: 0.83, 2: 0.85},
            "coherence_folded_T_given_S": {0: 0.87, 1: 0.86, 2: 0.88},
            "coherence_folded_second_T_given_S": {0: 0.52, 1: 0.50, 2: 0.54},
        }
    }
    agg = seeds.aggregate(values)
    text = seed_report.summary_markdown(agg)
    assert "| `coherence_folded_second_T_given_S` | 0.520 [" in text  # (0.52 + 0.50 + 0.54) / 3
    assert "| `coherence_folded_T_given_S` | 0.870 [" in text
    assert seed_report.comparison_figure(agg, tmp_path / "c.png").read_bytes()[:4] == b"\x89PNG"


def test_the_summary_only_aggregate_shows_the_same_summary_and_drops_the_rest(tmp_path):
    root = seed_sweep(tmp_path / "b", ["cvae", "avae_ts"], [0, 1, 2])
    agg = seeds.json_ready(seeds.aggregate(seeds.collect(root)))
    slim = seed_report.summary_only(agg)
    assert seed_report.summary_markdown(slim) == seed_report.summary_markdown(agg)
    kept = {m for rows in slim["summaries"].values() for m in rows}
    assert "coherence_T_given_S" in kept and "real/likeness_val_writers_legible" not in kept
    assert {c["metric"] for c in slim["comparisons"]} <= kept
    assert len(json.dumps(slim)) < len(json.dumps(agg))
