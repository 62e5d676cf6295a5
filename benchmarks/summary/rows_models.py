"""Rows of the benchmarks on the model side: the synthetic data build, training throughput and
time to quality, the importance-weighted estimator, and the commands' start-up."""

from __future__ import annotations

import math

from .common import Row


def prepare_rows(d: dict) -> list[Row]:
    render = d["render"]
    return [
        Row(
            f"full synthetic build ({sum(d['samples'].values()):,} samples)",
            f"{d['total_s']:.0f} s",
            "time budget",
            f"{d['budget_s']:.0f} s",
            d["total_s"] / d["budget_s"],
            "<= 1",
        ),
        Row(
            "trajectory renderer",
            f"{render['ours_per_s']:,.0f} images/s",
            "Pillow, 4x supersampling",
            f"{render['pillow_per_s']:,.0f} images/s",
            render["ours_per_s"] / render["pillow_per_s"],
            ">= 1",
        ),
    ]


def train_rows(d: dict) -> list[Row]:
    target = d["settings"]["target_ratio"]
    rows = [
        Row(
            f"training throughput, {family} (batch {f['batch_size']})",
            f"{f['lightning_samples_per_s']:,.0f} samples/s",
            "plain PyTorch loop",
            f"{f['plain_samples_per_s']:,.0f} samples/s",
            f["lightning_samples_per_s"] / f["plain_samples_per_s"],
            f">= {target}",
        )
        for family, f in d["families"].items()
    ]
    techniques = d.get("techniques")
    if techniques:
        reference = techniques["techniques"][techniques["reference"]]
        rows += [
            Row(
                f"MUSE training throughput, {name}",
                f"{t['samples_per_s']:,.0f} samples/s",
                f"plain loop, {techniques['reference']}",
                f"{reference['samples_per_s']:,.0f} samples/s",
                t["samples_per_s"] / reference["samples_per_s"],
                "> 1",
            )
            for name, t in techniques["techniques"].items()
            if name != techniques["reference"]
        ]
    quality = d.get("time_to_quality")
    if quality:
        ours, paper = quality["ours"], quality["paper"]

        def said(run: dict, decoding: str, level: str) -> str:
            minutes = run["cpu_min_to"][decoding].get(level)
            if minutes is not None:
                return f"{minutes:.1f} CPU min"
            return f"not reached in {run['cpu_min_spent']:.1f} CPU min"

        for decoding in quality["speedup"]:
            for level in map(str, quality["levels"]):
                speedup = quality["speedup"][decoding].get(level)
                if speedup is None and float(level) != quality["target"]:
                    continue  # a lower level ours did not reach either: nothing to compare
                bound = " (paper's run capped: ratio is an upper bound)"
                rows.append(
                    Row(
                        f"CPU time to MUSE T-from-S coherence {level} (folded, {decoding} "
                        f"decoding), experiment={ours['profile']}"
                        + (bound if speedup and speedup["lower_bound"] else ""),
                        said(ours, decoding, level),
                        "the paper's recipe (Adam 1e-4, batch 64, fp32)",
                        said(paper, decoding, level),
                        math.nan if speedup is None else 1 / speedup["ratio"],
                        "<= 0.2",
                    )
                )
    return rows


def evaluate_rows(d: dict) -> list[Row]:
    return [
        Row(
            f"importance-weighted estimator, {t['cell']} (K = {t['k']})",
            f"{t['estimator_samples_per_s']:,.0f} samples/s",
            "raw decoder forward",
            f"{t['decoder_samples_per_s']:,.0f} samples/s",
            t["estimator_samples_per_s"] / t["decoder_samples_per_s"],
            f">= {d['target_ratio']}",
        )
        for t in d["throughput"]
    ]


def startup_rows(d: dict) -> list[Row]:
    return [
        Row(
            f"start-up, `{r['case']}`",
            f"{r['median_s']:.2f} s",
            "python -c 'import torch'",
            f"{d['floor_s']:.2f} s",
            r["ratio"],
            f"<= {r['target_ratio']:g}" if r["target_ratio"] is not None else "-",
        )
        for r in d["rows"][1:]  # the first row is the floor itself
    ]


def reproducibility_rows(d: dict) -> list[Row]:
    what = f"{d['family']} seed {d['seed']} trained again ({d.get('label', 'run B')})"
    return [
        Row(
            f"{what}: median move of its {d['with_seed_sd']} reported metrics",
            f"{d['median_ratio']:.2f} sd",
            "the sd over its seeds",
            "1 sd",
            d["median_ratio"],
            "< 1",
        ),
        Row(
            f"{what}: metrics that move less than their seeds' sd",
            f"{d['within_1_sd']} of {d['with_seed_sd']} (largest {d['max_ratio']:.1f} sd)",
            "the sd over its seeds",
            "1 sd",
            d["max_ratio"],
        ),
    ]
