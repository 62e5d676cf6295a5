"""Tests of ``prg.evaluation.seeds``: the interval and the paired test against scipy, Holm against
a case worked by hand, blanks for missing cells, reading a sweep's folders."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from prg.errors import UsageError
from prg.evaluation import seed_report, seeds
from prg.files import write_json
from tests.helpers.seeds import seed_sweep


@pytest.mark.parametrize(
    "values", [[0.81, 0.84, 0.79, 0.86, 0.80], [-120.5, -118.0, -121.25], [1.0, 3.0]]
)
def test_t_interval_is_scipys(values):
    mean, low, high = seeds.t_interval(values)
    x = np.array(values)
    ref = stats.t.interval(0.95, len(x) - 1, loc=x.mean(), scale=stats.sem(x))
    assert mean == pytest.approx(x.mean())
    assert (low, high) == pytest.approx(ref)


def test_t_interval_of_one_value_has_none_and_of_constant_values_zero_width():
    mean, low, high = seeds.t_interval([0.5])
    assert mean == 0.5 and math.isnan(low) and math.isnan(high)
    assert seeds.t_interval([1.0, 1.0, 1.0]) == (1.0, 1.0, 1.0)


def test_paired_test_is_scipys_ttest_rel_on_the_shared_seeds():
    a = {0: 0.80, 1: 0.85, 2: 0.78, 3: 0.90, 4: 0.83, 7: 0.1}  # seed 7: a only
    b = {0: 0.75, 1: 0.80, 2: 0.79, 3: 0.82, 4: 0.80}
    result = seeds.paired_test(a, b)
    shared = [0, 1, 2, 3, 4]
    ref = stats.ttest_rel([a[s] for s in shared], [b[s] for s in shared])
    assert result["n"] == 5 and result["seeds"] == shared
    assert result["t"] == pytest.approx(ref.statistic)
    assert result["p"] == pytest.approx(ref.pvalue)
    assert (result["ci_low"], result["ci_high"]) == pytest.approx(tuple(ref.confidence_interval()))
    assert result["difference"] == pytest.approx(np.mean([a[s] - b[s] for s in shared]))


def test_a_difference_that_never_varies_is_not_tested():
    result = seeds.paired_test({0: 1.0, 1: 1.0, 2: 1.0}, {0: 1.0, 1: 1.0, 2: 1.0})
    assert math.isnan(result["p"]) and result["difference"] == 0.0


def test_holm_matches_a_case_worked_by_hand():
    # sorted p: 0.01 (x4 = 0.04), 0.02 (x3 = 0.06), 0.03 (x2 = 0.06, monotone), 0.04 (x1 = 0.06)
    adjusted, reject = seeds.holm([0.03, 0.01, float("nan"), 0.04, 0.02], alpha=0.05)
    assert adjusted[:2] == pytest.approx([0.06, 0.04])
    assert math.isnan(adjusted[2])
    assert adjusted[3:] == pytest.approx([0.06, 0.06])
    assert reject == [False, True, False, False, False]


def _values():
    """Three families over 5 seeds; avae_ti has no T|S cell (it takes no label)."""
    rng = np.random.default_rng(0)
    out = {}
    for family, level in (("cvae", 0.6), ("avae_ts", 0.62), ("avae_ti", 0.9)):
        noise = rng.normal(0, 0.01, 5)
        out[family] = {
            "coherence_T_given_I" if family == "avae_ti" else "coherence_T_given_S": {
                s: level + noise[s] for s in range(5)
            },
            "coherence_S_given_S": {s: 1.0 for s in range(5)},
            "logp_T": {s: -200 + 10 * level + noise[s] for s in range(5)},
            "train_cpu_min": {s: 2.0 + s / 10 for s in range(5)},
        }
    out["cvae"]["coherence_T_given_S"] = {s: 0.9 + (s % 2) * 0.01 for s in range(5)}
    return out


def test_aggregate_compares_pairs_within_a_metric_and_leaves_absent_cells_blank():
    agg = seeds.aggregate(_values())
    assert agg["families"] == ["cvae", "avae_ts", "avae_ti"] and agg["seeds"] == [0, 1, 2, 3, 4]
    assert "coherence_T_given_S" not in agg["summaries"]["avae_ti"]
    pairs = {(c["metric"], c["a"], c["b"]) for c in agg["comparisons"]}
    assert ("coherence_T_given_S", "cvae", "avae_ts") in pairs
    assert not any(
        c["metric"] == "coherence_T_given_S" and "avae_ti" in (c["a"], c["b"])
        for c in agg["comparisons"]
    )
    assert not any(c["metric"] == "train_cpu_min" for c in agg["comparisons"])  # times: no tests
    (ts,) = [c for c in agg["comparisons"] if c["metric"] == "coherence_T_given_S"]
    assert ts["significant"] and ts["p_holm"] == pytest.approx(ts["p"])  # one pair: unadjusted
    # three pairs of logp_T, Holm over them
    logp = [c for c in agg["comparisons"] if c["metric"] == "logp_T"]
    assert len(logp) == 3
    assert [c["p_holm"] for c in logp] == pytest.approx(seeds.holm([c["p"] for c in logp])[0])
    # every pair of S|S is 1.000 on every seed: untested
    assert all(
        math.isnan(c["p"]) and not c["significant"]
        for c in agg["comparisons"]
        if c["metric"] == "coherence_S_given_S"
    )
    text = seed_report.table_markdown(agg, "coherence")
    row = next(line for line in text.splitlines() if line.startswith("| `coherence_T_given_S`"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[3] == ""  # avae_ti: blank, not 0
    assert cells[1].startswith("0.904 [")
    assert "PRG_CVAE(T,S) > PRG_AVAE(T,S)" in text
    assert "Seeds: PRG_CVAE(T,S) 5 (0-4)" in text


def test_tables_sort_metrics_where_the_demo_reports_them():
    assert seeds.table_of("logp_T_given_S_model_std") == ["table1"]
    assert seeds.table_of("coherence_T_given_SI") == ["coherence", "robustness"]
    assert seeds.table_of("coherence_folded_imputed_S_given_T") == ["coherence"]
    assert seeds.table_of("coherence_T_given_I_shift2") == ["robustness"]
    assert seeds.table_of("roughness_ratio_imputed_T_given_S") == ["roughness"]
    assert seeds.table_of("likeness_hand_legible") == ["likeness"]
    assert seeds.table_of("evaluate_cpu_min") == ["timing"]
    assert seeds.table_of("style_k1_ratio") == []


def test_collect_reads_a_sweep_and_names_what_is_missing(tmp_path):
    root = seed_sweep(tmp_path / "baselines")
    # an evaluation under way: its hidden staging folder is not a family
    write_json(root / "seed0" / "reports" / ".muse.tmp-99" / "metrics.json", {"muse/x": 1.0})
    values = seeds.collect(root)
    assert set(values) == {"cvae", "avae_ts", "real"}
    assert values["cvae"]["train_cpu_min"] == {0: 2.0, 1: 121 / 60, 2: 122 / 60}
    assert values["avae_ts"]["evaluate_wall_min"][1] == pytest.approx(1 / 3)
    assert values["real"]["likeness_val_writers_legible"] == {0: 0.9, 1: 0.9, 2: 0.9}
    assert "classifier/traj/test_accuracy" not in values["cvae"]
    with pytest.raises(UsageError, match=r"seed3/reports/cvae/metrics\.json does not exist"):
        seeds.collect(root, ["cvae"], [0, 3])
    with pytest.raises(UsageError, match="no evaluated seed"):
        seeds.collect(tmp_path / "empty")
