"""Results over training seeds: each family's metrics as mean and 95 % t-interval over the seeds
it was trained with, and pairwise comparisons between families, paired over seeds and
Holm-corrected (``make baselines``, :mod:`prg.commands.baselines`).

Pure functions from per-seed values to an aggregate (:func:`aggregate`), from the aggregate to
report texts (:func:`report_texts`) and a figure (:func:`comparison_figure`); reading the
folders of a sweep is :func:`collect`.

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

from prg.evaluation.reports import _md_table, title, to_csv
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


def _get(d: Mapping[str, Any], key: str) -> float:
    value = d.get(key)
    return math.nan if value is None else float(value)


# ---- reports ---------------------------------------------------------------------------------
def cell_text(summary: Mapping[str, Any] | None, fmt: str) -> str:
    """``mean [low, high]``; the mean alone without an interval; blank without a value."""
    if summary is None:
        return ""
    mean, low, high = (_get(summary, k) for k in ("mean", "ci_low", "ci_high"))
    if not math.isfinite(mean):
        return ""
    if not (math.isfinite(low) and math.isfinite(high)):
        return format(mean, fmt)
    return f"{mean:{fmt}} [{low:{fmt}}, {high:{fmt}}]"


def seeds_text(seeds: Sequence[int]) -> str:
    """``0-4`` for a run of seeds, else ``0, 2, 3``."""
    seeds = sorted(seeds)
    if len(seeds) > 2 and seeds == list(range(seeds[0], seeds[-1] + 1)):
        return f"{seeds[0]}-{seeds[-1]}"
    return ", ".join(map(str, seeds))


def _column(family: str) -> str:
    return "real letters" if family == REFERENCE else title(family)


def table_rows(agg: Mapping[str, Any], table: str) -> list[dict[str, Any]]:
    """Long rows (family, metric, mean, ci_low, ci_high, sd, n, seeds) of one table."""
    rows = []
    for metric in agg["tables"][table]:
        for family in agg["families"]:
            s = agg["summaries"][family].get(metric)
            if s is not None:
                rows.append(
                    {
                        "family": family,
                        "metric": metric,
                        **{k: s[k] for k in ("mean", "ci_low", "ci_high", "sd", "n")},
                        "seeds": " ".join(map(str, s["seeds"])),
                    }
                )
    return rows


def table_markdown(
    agg: Mapping[str, Any], table: str, metrics: Sequence[str] | None = None, heading: str = "#"
) -> str:
    """One table: a row per metric, a column per family (``mean [95 % CI]``, blank where the
    family does not have the metric), the seeds of each family and the significant
    differences."""
    name, text, _, compared, fmt = TABLES[table]
    metrics = list(agg["tables"][table] if metrics is None else metrics)
    families = [f for f in agg["families"] if any(m in agg["summaries"][f] for m in metrics)]
    body = [
        [f"`{m}`", *(cell_text(agg["summaries"][f].get(m), fmt) for f in families)] for m in metrics
    ]
    level = f"{agg['level']:.0%}".replace("%", " %")
    parts = [
        f"{heading} {name}",
        f"{text} Mean over training seeds [{level} t-interval]; blank: the family does not "
        "have that cell. " + seeds_line(agg, families),
        _md_table(["metric", *map(_column, families)], body) if metrics else "No metrics.",
    ]
    if compared and metrics:
        parts.append(significance_text(agg, metrics, fmt))
    return "\n\n".join(parts) + "\n"


def seeds_line(agg: Mapping[str, Any], families: Sequence[str]) -> str:
    """``Seeds: PRG_CVAE(T,S) 5 (0-4), ...`` (the most seeds any metric of a family has)."""
    texts = []
    for family in families:
        seeds = max((s["seeds"] for s in agg["summaries"][family].values()), key=len, default=[])
        texts.append(f"{_column(family)} {len(seeds)} ({seeds_text(seeds)})")
    return "Seeds: " + "; ".join(texts) + "."


def significance_text(agg: Mapping[str, Any], metrics: Sequence[str], fmt: str) -> str:
    """The significant pairwise differences of ``metrics``, one line per metric that has one."""
    wanted = set(metrics)
    lines, tested, untested = [], 0, 0
    for metric in metrics:
        mine = [c for c in agg["comparisons"] if c["metric"] == metric]
        tested += sum(_get(c, "p") == _get(c, "p") for c in mine)
        untested += sum(_get(c, "p") != _get(c, "p") for c in mine)
        shown = []
        for c in (c for c in mine if c["significant"]):
            higher, lower = (c["a"], c["b"]) if c["difference"] > 0 else (c["b"], c["a"])
            sign = 1 if c["difference"] > 0 else -1
            low, high = sorted((sign * c["ci_low"], sign * c["ci_high"]))
            shown.append(
                f"{title(higher)} > {title(lower)} by {sign * c['difference']:{fmt}} "
                f"[{low:{fmt}}, {high:{fmt}}], p_Holm = {_p_text(c['p_holm'])}"
            )
        if shown:
            lines.append(f"- `{metric}`: " + "; ".join(shown))
    alpha = agg["alpha"]
    head = (
        f"Pairwise differences (paired t-test over the seeds both families were trained with, "
        f"Holm-adjusted over the pairs of each metric, significant where p_Holm < {alpha:g}): "
        f"{sum(1 for c in agg['comparisons'] if c['metric'] in wanted and c['significant'])} of "
        f"{tested} significant"
        + (
            f"; {untested} untested (fewer than two seeds in common, or the same difference on "
            "every seed)"
            if untested
            else ""
        )
        + "; every comparison in comparisons.csv."
    )
    return "\n".join([head, "", *lines]) if lines else head


def _p_text(p: float) -> str:
    if p is None or not math.isfinite(p):
        return "n/a"
    return f"{p:.2g}" if p < 0.001 else f"{p:.3f}"


COMPARISON_COLUMNS = (
    "metric",
    "a",
    "b",
    "n",
    "difference",
    "ci_low",
    "ci_high",
    "t",
    "df",
    "p",
    "p_holm",
    "significant",
)
SUMMARY_COLUMNS = ("family", "metric", "mean", "ci_low", "ci_high", "sd", "n", "seeds")


def report_texts(agg: Mapping[str, Any], wall: str = "") -> dict[str, str]:
    """File name -> text of the aggregated reports: ``<table>.md`` and ``.csv`` per table,
    ``comparisons.csv`` and ``index.md`` (``wall``: a line on how long the sweep took)."""
    from prg.files import json_text

    texts = {}
    for table in TABLES:
        texts[f"{table}.md"] = table_markdown(agg, table)
        texts[f"{table}.csv"] = to_csv(table_rows(agg, table), SUMMARY_COLUMNS)
    texts["comparisons.csv"] = to_csv(
        [{**c, "significant": str(c["significant"]).lower()} for c in agg["comparisons"]],
        COMPARISON_COLUMNS,
    )
    texts["index.md"] = (
        "# Baselines over seeds\n\n"
        + (wall + "\n\n" if wall else "")
        + "Tables: "
        + ", ".join(f"[{t}]({t}.md)" for t in TABLES)
        + "; every pairwise comparison: comparisons.csv; figure: comparison.png.\n\n"
        + summary_markdown(agg, heading="##")
    )
    texts["aggregate.json"] = json_text(json_ready(agg))
    return texts


# the cells shown in the summary and the figure: cross-modal coherence and roughness (posterior
# mean, exact), the Table I conditionals, the times
_CROSS = re.compile(r"coherence_([TSI])_given_([TSI]+)")
SUMMARY_TABLE1 = ("logp_T_given_S", "logp_T_given_I", "logp_S_given_T", "logp_I_given_T")


_CROSS_FOLDED = re.compile(r"coherence_folded(?:_second)?_([TSI])_given_([TSI]+)")


def cross_modal(metrics: Iterable[str], folded: bool = False) -> list[str]:
    """The cross-modal coherence cells of the posterior mean (the target not among the inputs):
    read exactly by the first classifier, or (``folded``) with shape twins folded by the first
    and by the second classifier (``coherence_folded_...``, ``coherence_folded_second_...``)."""
    pattern = _CROSS_FOLDED if folded else _CROSS
    out = []
    for m in metrics:
        match = pattern.fullmatch(m)
        if match and match[1] not in match[2]:
            out.append(m)
    return out


def summary_tables(agg: Mapping[str, Any]) -> list[tuple[str, list[str]]]:
    """The short version's tables, (table, metrics) each: cross-modal coherence (exact, then
    folded by both classifiers: where they part, the letters are read differently by the points'
    order and by the shape, docs/evaluation.md), roughness, the Table I conditionals, times."""
    metrics = sorted({m for t in agg["tables"].values() for m in t})
    return [
        ("coherence", cross_modal(metrics)),
        ("coherence", cross_modal(metrics, folded=True)),
        ("roughness", [m for m in agg["tables"]["roughness"] if "_imputed" not in m]),
        ("table1", [m for m in SUMMARY_TABLE1 if m in metrics]),
        ("timing", list(agg["tables"]["timing"])),
    ]


def summary_markdown(agg: Mapping[str, Any], heading: str = "####") -> str:
    """The short version (:func:`summary_tables`) as markdown."""
    return "\n".join(table_markdown(agg, t, m, heading) for t, m in summary_tables(agg))


def summary_only(agg: Mapping[str, Any]) -> dict[str, Any]:
    """``agg`` cut down to what :func:`summary_markdown` shows (the summaries, tables and
    comparisons of its metrics): the docs' snapshot, a tenth of the whole aggregate's size."""
    keep: dict[str, list[str]] = {}
    for table, metrics in summary_tables(agg):
        keep.setdefault(table, []).extend(m for m in metrics if m not in keep[table])
    shown = {m for metrics in keep.values() for m in metrics}
    return {
        **agg,
        "tables": {t: [m for m in agg["tables"][t] if m in shown] for t in agg["tables"]},
        "summaries": {
            f: {m: row for m, row in rows.items() if m in shown}
            for f, rows in agg["summaries"].items()
        },
        "comparisons": [c for c in agg["comparisons"] if c["metric"] in shown],
    }


# ---- the figure ------------------------------------------------------------------------------
def comparison_figure(agg: Mapping[str, Any], path: Path) -> Path:
    """Cross-modal coherence and roughness ratio per family: bars at the mean over seeds, error
    bars the t-interval (none for one seed); written atomically to ``path`` (PNG)."""
    from prg.files import atomic_path
    from prg.plotting import distinct_colours, pyplot

    plt = pyplot()
    metrics = {m for t in agg["tables"].values() for m in t}
    panels = [
        ("cross-modal coherence (posterior mean)", cross_modal(sorted(metrics)), (0, 1.05)),
        (
            "the same, shape twins folded: by the first classifier and the second (2nd)",
            cross_modal(sorted(metrics), folded=True),
            (0, 1.05),
        ),
        (
            "roughness ratio (1: as smooth as the test letters)",
            [m for m in agg["tables"]["roughness"] if "_imputed" not in m],
            None,
        ),
    ]
    panels = [p for p in panels if p[1]]
    families = [f for f in agg["families"] if f != REFERENCE]
    colours = distinct_colours(len(families)) / 255
    fig, axes = plt.subplots(
        len(panels),
        1,
        figsize=(
            min(18, max(6, 1.1 * max((len(p[1]) for p in panels), default=1) + 2)),
            3.2 * len(panels),
        ),
        squeeze=False,
    )
    width = min(0.25, 0.8 / max(1, len(families)))
    for ax, (label, cells, ylim) in zip(axes[:, 0], panels, strict=True):
        x = np.arange(len(cells))
        for j, metric in enumerate(cells):  # each cell's bars centred on it: only who has it
            having = [
                (i, agg["summaries"][f][metric])
                for i, f in enumerate(families)
                if metric in agg["summaries"][f]
                and math.isfinite(_get(agg["summaries"][f][metric], "mean"))
            ]
            for k, (i, row) in enumerate(having):
                where = j + (k - (len(having) - 1) / 2) * width
                mean, low, high = (_get(row, key) for key in ("mean", "ci_low", "ci_high"))
                ax.bar(where, mean, width, color=colours[i], label=title(families[i]))
                if math.isfinite(low) and math.isfinite(high):
                    ax.errorbar(
                        where,
                        mean,
                        yerr=[[mean - low], [high - mean]],
                        fmt="none",
                        ecolor="black",
                        elinewidth=1,
                        capsize=2,
                    )
        ax.set_xticks(x, [_cell_label(m) for m in cells], fontsize=8)
        ax.set_xlim(-0.6, len(cells) - 0.4)  # a cell's room is the same with one cell or ten
        ax.set_title(label, fontsize=10)
        if ylim:
            ax.set_ylim(*ylim)
        else:
            ax.axhline(1.0, color="grey", linewidth=0.8, linestyle="--")
        ax.grid(axis="y", alpha=0.3)
    level = f"{agg['level']:.0%}".replace("%", " %")
    shown = {}  # one legend entry per family, in the families' order
    for ax in axes[:, 0]:
        for handle, name in zip(*ax.get_legend_handles_labels(), strict=True):
            shown.setdefault(name, handle)
    order = [title(f) for f in families if title(f) in shown]
    handles, labels = [shown[n] for n in order], order
    fig.legend(
        handles,
        labels,
        fontsize=8,
        ncol=min(7, len(families)),
        loc="upper center",
        bbox_to_anchor=(0.5, 0.95),
        frameon=False,
    )
    fig.suptitle(
        f"Mean over seeds {seeds_text(agg['seeds'])}, error bars: {level} t-interval", fontsize=10
    )
    fig.tight_layout(rect=(0, 0, 1, 0.9))
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)
    return path


def _cell_label(metric: str) -> str:
    """``coherence_T_given_SI`` -> ``T|S,I``; ``roughness_ratio_T_given_S`` -> ``T|S``."""
    match = re.search(r"([TSI])_given_([TSI]+)$", metric)
    second = " 2nd" if "_second_" in metric else ""
    return f"{match[1]}|{','.join(match[2])}{second}" if match else metric
