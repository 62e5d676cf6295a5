"""Results over training seeds: each family's metrics as mean and 95 % t-interval over the seeds
it was trained with, and pairwise comparisons between families, paired over seeds and
Holm-corrected (``make baselines``, :mod:`prg.commands.baselines`).

Pure functions from per-seed values to an aggregate (:func:`aggregate`); reading the folders of
a sweep is :func:`collect`. The aggregate's tables, summary and figure are
:mod:`prg.evaluation.seed_report`.

The statistics:

- per family and metric: the mean over seeds and its two-sided t-interval at ``level``
  (mean +- t(1 - (1 - level) / 2, n - 1) * sd / sqrt(n)); one seed gives a mean and no interval,
  values that do not vary over seeds an interval of zero width;
- per metric, every pair of families that both have it: the paired t-test of the per-seed
  differences (only seeds both were trained with), with the t-interval of the mean difference;
  the pairs of one metric are one family of comparisons, their p values Holm-adjusted
  (``statsmodels.stats.multitest.multipletests``) and a difference called significant when its
  adjusted p is below ``alpha``. A difference that is the same on every seed (e.g. two
  families at coherence 1.000 on every seed) has no t statistic: it is reported untested and
  does not count among the comparisons.

A cell a family does not have (an input subset it cannot take, a Table I cell it cannot
estimate) is blank in the tables and absent from the JSON, never zero.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from prg.files import read_json

LEVEL = 0.95
ALPHA = 0.05
REFERENCE = "real"  # the likeness table's real letters: a column, never compared
SEED_FOLDER = re.compile(r"^seed(\d+)$")

# per-seed values: family -> metric -> seed -> value
Values = dict[str, dict[str, dict[int, float]]]

_ROBUST = re.compile(r"coherence(?:_folded)?_(?:T_given_[TSI]+|[TSI]_given_I_shift\d+)")
TIMING = ("train_cpu_min", "train_wall_min", "epochs", "evaluate_cpu_min", "evaluate_wall_min")

# table name -> (title, text under the title, which metrics, compared between families, format)
TABLES: dict[str, tuple[str, str, Callable[[str], bool], bool, str]] = {
    "table1": (
        "Table I: importance-weighted log-likelihoods over seeds",
        "Nats, higher is better; trajectory targets under the unit-variance Gaussian of the "
        "demo's Table I (`_model_std`: each model's own std).",
        lambda m: m.startswith("logp_"),
        True,
        ".2f",
    ),
    "coherence": (
        "Cross-modal coherence over seeds",
        "Fraction of generated samples the independent classifier assigns to the conditioning "
        "class; `folded`: shape twins counted right; `sampled`: latents drawn at T = 1; "
        "`imputed`: MUSE's posterior mean after imputing the missing modalities.",
        lambda m: m.startswith("coherence") and "_shift" not in m,
        True,
        ".3f",
    ),
    "robustness": (
        "Missing-modality robustness over seeds",
        "Coherence of the trajectories generated from each input subset a family takes "
        "(posterior mean), and of what is generated from test images moved off-centre by up to "
        "1 and 2 pixels (`_shift1`, `_shift2`).",
        lambda m: _ROBUST.fullmatch(m) is not None,
        True,
        ".3f",
    ),
    "roughness": (
        "Roughness of decoded letters over seeds",
        "Median roughness of the letters decoded from labels or images over that of the same "
        "test letters (1: as smooth as the data; `prg/evaluation/smoothness.py`).",
        lambda m: m.startswith("roughness_ratio_"),
        True,
        ".2f",
    ),
    "likeness": (
        "Likeness to held-out writers' letters over seeds",
        "Per decoding mode: legible, k-NN precision and recall, c2st (0.5: indistinguishable) "
        "and spread, as in the demo's likeness.md; `real`: real letters scored the same way.",
        lambda m: m.startswith("likeness_"),
        True,
        ".2f",
    ),
    "timing": (
        "Time to train (quick profile) and to evaluate",
        "Minutes per family and seed: CPU time of all threads and wall time of the fit "
        "(`prg-train`'s metrics.json), epochs, and CPU (the process and its children) and "
        "wall time of that family's `prg-evaluate`.",
        lambda m: m in TIMING,
        False,
        ".1f",
    ),
}


# ---- statistics ------------------------------------------------------------------------------
def _constant(x: np.ndarray) -> bool:
    return len(x) == 0 or float(np.ptp(x)) <= 1e-12 * max(1.0, float(np.max(np.abs(x))))


def t_interval(values: Sequence[float], level: float = LEVEL) -> tuple[float, float, float]:
    """(mean, low, high): the two-sided t-interval of the mean of ``values`` at ``level``; low
    and high NaN for fewer than 2 values, both the mean when the values do not vary."""
    x = np.asarray(values, dtype=float)
    if len(x) == 0:
        return math.nan, math.nan, math.nan
    mean = float(x.mean())
    if len(x) < 2:
        return mean, math.nan, math.nan
    if _constant(x):
        return mean, mean, mean
    half = float(stats.t.ppf(0.5 + level / 2, len(x) - 1) * x.std(ddof=1) / math.sqrt(len(x)))
    return mean, mean - half, mean + half


def summarise(by_seed: Mapping[int, float], level: float = LEVEL) -> dict[str, Any]:
    """One family's metric over its seeds: mean, t-interval, sd, n and the seeds."""
    seeds = sorted(by_seed)
    x = [by_seed[s] for s in seeds]
    mean, low, high = t_interval(x, level)
    sd = float(np.std(x, ddof=1)) if len(x) > 1 else math.nan
    return {"mean": mean, "ci_low": low, "ci_high": high, "sd": sd, "n": len(x), "seeds": seeds}


def paired_test(
    a: Mapping[int, float], b: Mapping[int, float], level: float = LEVEL
) -> dict[str, Any]:
    """The paired t-test of ``a - b`` over the seeds both have: n, the mean difference and its
    t-interval, t, df and the two-sided p (t and p NaN when the difference does not vary or
    fewer than 2 seeds are shared)."""
    from statsmodels.stats.weightstats import DescrStatsW

    seeds = sorted(set(a) & set(b))
    d = np.array([a[s] - b[s] for s in seeds], dtype=float)
    out = {"n": len(d), "seeds": seeds, "difference": float(d.mean()) if len(d) else math.nan}
    if len(d) < 2 or _constant(d):
        _, low, high = t_interval(d, level)
        return {
            **out,
            "ci_low": low,
            "ci_high": high,
            "t": math.nan,
            "df": len(d) - 1,
            "p": math.nan,
        }
    described = DescrStatsW(d)
    t, p, df = described.ttest_mean(0.0)
    low, high = described.tconfint_mean(alpha=1 - level)
    return {
        **out,
        "ci_low": float(low),
        "ci_high": float(high),
        "t": float(t),
        "df": int(df),
        "p": float(p),
    }


def holm(pvalues: Sequence[float], alpha: float = ALPHA) -> tuple[list[float], list[bool]]:
    """Holm-adjusted p values and rejections at ``alpha`` of the finite ``pvalues``; a NaN p
    stays NaN, is not rejected and does not count among the comparisons."""
    from statsmodels.stats.multitest import multipletests

    p = np.asarray(pvalues, dtype=float)
    adjusted, reject = np.full(len(p), math.nan), np.zeros(len(p), dtype=bool)
    finite = np.isfinite(p)
    if finite.any():
        reject[finite], adjusted[finite] = multipletests(p[finite], alpha, method="holm")[:2]
    return [float(x) for x in adjusted], [bool(x) for x in reject]


# ---- reading a sweep -------------------------------------------------------------------------
def seed_folders(root: Path) -> dict[int, Path]:
    """seed -> ``root/seed<s>`` for each such folder."""
    found = {}
    if root.is_dir():
        for path in root.iterdir():
            match = SEED_FOLDER.match(path.name)
            if match and path.is_dir():
                found[int(match[1])] = path
    return dict(sorted(found.items()))


def evaluation_dir(root: Path, seed: int, family: str) -> Path:
    """Where one family's evaluation of one seed is written."""
    return root / f"seed{seed}" / "reports" / family


def family_values(
    train: Mapping[str, Any], evaluation: Mapping[str, Any], timing: Mapping[str, Any], family: str
) -> dict[str, dict[str, float]]:
    """name -> metric -> value of one (family, seed): the family's ``<family>/<metric>``
    evaluation metrics, the likeness reference's (``real/...``) and the timing metrics."""
    out: dict[str, dict[str, float]] = {family: {}, REFERENCE: {}}
    for key, value in evaluation.items():
        name, _, metric = key.partition("/")
        if name in out and _number(value):
            out[name][metric] = float(value)
    mine = out[family]
    for key, scale in (("fit_cpu_s", 60), ("fit_wall_s", 60), ("epochs", 1)):
        if _number(train.get(key)):
            name = {"fit_cpu_s": "train_cpu_min", "fit_wall_s": "train_wall_min"}.get(key, key)
            mine[name] = float(train[key]) / scale
    for key in ("cpu_s", "wall_s"):
        if _number(timing.get(key)):
            mine[f"evaluate_{key[:-2]}_min"] = float(timing[key]) / 60
    return out


def _number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def collect(
    root: Path, families: Iterable[str] | None = None, seeds: Iterable[int] | None = None
) -> Values:
    """family -> metric -> seed -> value of a sweep under ``root`` (``seed<s>/<family>/``
    ``metrics.json`` from training, ``seed<s>/reports/<family>/metrics.json`` and ``timing.json``
    from evaluation). Given ``families`` and ``seeds``, each must be there (one
    :class:`~prg.errors.UsageError` naming the first missing file); else every evaluated
    (family, seed) found is read."""
    from prg.errors import UsageError

    folders = seed_folders(root)
    chosen = sorted(folders) if seeds is None else list(seeds)
    values: Values = {}
    for seed in chosen:
        reports = root / f"seed{seed}" / "reports"
        if families is None:
            names = sorted(p.name for p in reports.iterdir()) if reports.is_dir() else []
            names = [
                f
                for f in names
                if not f.startswith(".") and (reports / f / "metrics.json").is_file()
            ]  # a hidden name: a staging folder of an evaluation under way
        else:
            names = list(families)
        for family in names:
            where = evaluation_dir(root, seed, family)
            if not (where / "metrics.json").is_file():
                raise UsageError(
                    f"{where / 'metrics.json'} does not exist: evaluate the sweep first "
                    "(python -m prg.commands.baselines evaluate)"
                )
            evaluation = read_json(where / "metrics.json", "evaluation metrics")
            train_file = root / f"seed{seed}" / family / "metrics.json"
            train = read_json(train_file, "training metrics") if train_file.is_file() else {}
            timing_file = where / "timing.json"
            timing = read_json(timing_file, "timing") if timing_file.is_file() else {}
            for name, metrics in family_values(train, evaluation, timing, family).items():
                for metric, value in metrics.items():
                    values.setdefault(name, {}).setdefault(metric, {})[seed] = value
    if not values:
        raise UsageError(f"no evaluated seed under {root}: nothing to aggregate")
    return values


# ---- the aggregate ---------------------------------------------------------------------------
def table_of(metric: str) -> list[str]:
    """The tables a metric is shown in (coherence cells of trajectories also in robustness)."""
    return [name for name, (_, _, member, _, _) in TABLES.items() if member(metric)]


def _ordered(names: Iterable[str]) -> list[str]:
    """Families in the paper's order, then the others as given, the reference last."""
    from prg.evaluation.reports import FAMILY_TITLES

    names = list(dict.fromkeys(names))
    known = [f for f in FAMILY_TITLES if f in names]
    rest = [f for f in names if f not in FAMILY_TITLES and f != REFERENCE]
    return known + rest + ([REFERENCE] if REFERENCE in names else [])


def aggregate(values: Values, level: float = LEVEL, alpha: float = ALPHA) -> dict[str, Any]:
    """Summaries per family and metric, the metrics of each table and the pairwise comparisons
    (per metric, Holm over its pairs) of the tables that compare families."""
    families = _ordered(values)
    summaries = {
        f: {m: summarise(by_seed, level) for m, by_seed in sorted(values[f].items())}
        for f in families
    }
    metrics = sorted({m for f in families for m in values[f]})
    tables = {name: [m for m in metrics if name in table_of(m)] for name in TABLES}
    compared = [f for f in families if f != REFERENCE]
    comparisons = []
    for metric in metrics:
        if not any(TABLES[t][3] for t in table_of(metric)):
            continue
        having = [f for f in compared if metric in values[f]]
        pairs = [(a, b) for i, a in enumerate(having) for b in having[i + 1 :]]
        tests = [paired_test(values[a][metric], values[b][metric], level) for a, b in pairs]
        adjusted, reject = holm([t["p"] for t in tests], alpha)
        for (a, b), test, p_holm, significant in zip(pairs, tests, adjusted, reject, strict=True):
            comparisons.append(
                {
                    "metric": metric,
                    "a": a,
                    "b": b,
                    **test,
                    "p_holm": p_holm,
                    "significant": significant,
                }
            )
    seeds = sorted({s for f in families for m in values[f].values() for s in m})
    return {
        "level": level,
        "alpha": alpha,
        "families": families,
        "seeds": seeds,
        "tables": tables,
        "summaries": summaries,
        "comparisons": comparisons,
    }


def json_ready(obj: Any) -> Any:
    """``obj`` with every NaN as None (JSON has no NaN)."""
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, Mapping):
        return {k: json_ready(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [json_ready(v) for v in obj]
    return obj
