"""Reports of results over training seeds: the tables (markdown, CSV), the summary the docs
show, and the comparison figure, all pure functions of an aggregate
(:func:`prg.evaluation.seeds.aggregate`) and written by ``make baselines``
(:mod:`prg.commands.baselines`).

A cell a family does not have is blank in the tables, never zero; a mean over one seed is shown
without an interval.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from prg.evaluation.reports import _md_table, title, to_csv
from prg.evaluation.seeds import REFERENCE, TABLES, json_ready


def _get(d: Mapping[str, Any], key: str) -> float:
    value = d.get(key)
    return math.nan if value is None else float(value)


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
