"""Tests of ``benchmarks/bench_reproducibility.py``: the move of each reported metric against
the seeds' standard deviation, worked by hand; times are not reported metrics."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import pytest

from prg.files import write_json

HERE = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_reproducibility.py"
spec = importlib.util.spec_from_file_location("bench_reproducibility", HERE)
bench = importlib.util.module_from_spec(spec)
spec.loader.exec_module(bench)


def test_each_move_is_a_ratio_to_the_seeds_sd():
    a = {"coherence_T_given_S": 0.80, "roughness_ratio_T_given_S": 1.30, "train_cpu_min": 2.0}
    b = {"coherence_T_given_S": 0.83, "roughness_ratio_T_given_S": 1.30, "train_cpu_min": 9.0}
    spread = {
        "coherence_T_given_S": {0: 0.80, 1: 0.84, 2: 0.82},  # sd 0.02
        "roughness_ratio_T_given_S": {0: 1.3},  # one seed: no sd
    }
    rows = {r["metric"]: r for r in bench.compare(a, b, spread)}
    assert set(rows) == {"coherence_T_given_S", "roughness_ratio_T_given_S"}  # no times
    assert rows["coherence_T_given_S"]["diff"] == pytest.approx(0.03)
    assert rows["coherence_T_given_S"]["ratio"] == pytest.approx(1.5)
    assert math.isnan(rows["roughness_ratio_T_given_S"]["sd"])
    result = bench.summary(list(rows.values()))
    assert (result["metrics"], result["with_seed_sd"], result["within_1_sd"]) == (2, 1, 0)
    assert result["within_2_sd"] == 1 and result["max_ratio"] == pytest.approx(1.5)


def test_runs_without_a_common_seed_are_refused_in_one_line(tmp_path, capsys):
    for run, seed in (("a", 0), ("b", 1)):
        write_json(tmp_path / run / f"seed{seed}/reports/cvae/metrics.json", {"cvae/x": 1.0})
    write_json(tmp_path / "s/seed0/reports/cvae/metrics.json", {"cvae/x": 1.0})
    args = [str(tmp_path / "a"), str(tmp_path / "b"), "--seeds", str(tmp_path / "s")]
    assert bench.main(args) == 2
    assert capsys.readouterr().err.strip() == (
        "bench_reproducibility: the runs have seeds [0] and [1]: give --seed, one seed both have"
    )
