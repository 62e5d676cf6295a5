"""The demo pipeline's section (``make demo``: quick profile, synthetic data) and the converged
profile's (``make converged``), from their snapshots under ``benchmarks/results/``."""

from __future__ import annotations

from pathlib import Path

from prg.evaluation.reports import FAMILY_TITLES

from .common import CONVERGED, DEMO, read_json, table
from .evaluation_tables import coherence_markdown, likeness_markdown, table1_markdown
from .snapshot import CONVERGED_SOURCES, DEMO_SOURCES, PIPELINE_FAMILIES


def demo_markdown(demo: Path = DEMO) -> str:
    """Tables of the demo pipeline's results (quick profile, synthetic data)."""
    d = {name: read_json(demo / name) for name in DEMO_SOURCES}
    evaluate = d["evaluate.json"]
    models = {family: d[f"models_{family}.json"] for family in PIPELINE_FAMILIES}
    dictaphone = d["dictaphone.json"]
    table2 = table(
        ["word", "channel", "perceived", "written", "DMP error", "seconds"],
        [
            [
                r["word"],
                r["channel"],
                r["perceived"],
                r["written"],
                f"{r['dmp_rmse_mm']:.3f} mm",
                f"{r['seconds']:.2f}",
            ]
            for r in dictaphone["rows"]
        ],
    )
    sim = d["simulate.json"]
    study = d["study.json"]["studies"]["readability"]
    classifiers = d["classifiers.json"]
    prepare = d["prepare.json"]
    likeness = likeness_markdown(evaluate)  # none for a snapshot made before it
    lines = [
        f"Synthetic data: {prepare['train_samples']:,} / {prepare['val_samples']:,} / "
        f"{prepare['test_samples']:,} train / val / test samples; coherence classifiers "
        f"{_accuracy_text(classifiers)}.",
        "",
        table1_markdown(evaluate, models),
        "",
        coherence_markdown(evaluate),
        "",
        *([likeness, ""] if likeness else []),
        f"**Table II** (`prg-dictaphone`, MUSE): the words from speech (whisper, lexicon, "
        f"rescoring) and from the letter images alone (images read right: "
        f"{dictaphone['image_read_accuracy']:.0%}{_folded_reading(dictaphone)}):",
        "",
        table2,
        "",
        f"**Robot** (`prg-simulate`, {sim['robot']} writes '{sim['text']}'): "
        f"{sim['word_width_cm']:.1f} x {sim['word_height_cm']:.1f} cm in {sim['writing_s']:.1f} s, "
        f"pen tracking error mean {1000 * sim['tracking_error_mean_mm']:.1f} um "
        f"(max {1000 * sim['tracking_error_max_mm']:.0f} um), {sim['ink_strokes']} ink stroke(s), "
        f"largest ink gap {sim['max_ink_gap_mm']:.2f} mm, real-time factor "
        f"{sim['realtime_factor']:.1f}.",
        "",
        f"**Readability study on simulated participants** (`prg-study`, paper's rates): "
        f"robot - human difference {study['difference']:+.3f} "
        f"(95 % CI {study['difference_ci'][0]:+.3f} to {study['difference_ci'][1]:+.3f}), "
        f"margin {study['margin']}: {study['verdict']} ({study['primary']}).",
    ]
    return "\n".join(lines)


def _folded_reading(dictaphone: dict) -> str:
    """``, up to shape twins (i/l ...): N%`` where the snapshot has it (older ones do not)."""
    folded = dictaphone.get("image_read_accuracy_folded")
    if folded is None:
        return ""
    return (
        f"; up to shape twins such as a dotless i and an l, as coherence folds them: {folded:.0%}"
    )


def _minutes(seconds: float) -> str:
    return f"{seconds / 60:.1f} min"


def converged_markdown(converged: Path = CONVERGED) -> str:
    """Tables of the converged profile's models (``make converged``), or a line saying how."""
    if not (converged / "run.json").is_file():
        return (
            "No converged snapshot yet: `make converged`, then "
            "`python benchmarks/summarize.py --snapshot-converged converged`."
        )
    d = {name: read_json(converged / name) for name in CONVERGED_SOURCES}
    run, evaluate = d["run.json"], d["evaluate.json"]
    models = {family: d[f"models_{family}.json"] for family in PIPELINE_FAMILIES}
    settings, stages = run["settings"], run["stages"]
    fit = run.get("fit", {})
    costs = ", ".join(
        f"{FAMILY_TITLES[f]} {_minutes(fit[f]['fit_cpu_s'])} CPU ({fit[f]['epochs']:.0f} epochs)"
        for f in PIPELINE_FAMILIES
        if f in fit
    )
    n_likelihood = settings.get("n_test_likelihood") or "all"
    n_test = settings.get("n_test") or "all"
    return "\n".join(
        [
            f"`{run['command']}` on {run['device']}: "
            f"{_minutes(run['total_seconds'])} wall in all"
            + (
                f"; training {_minutes(stages['train']['seconds'])} wall for the four families "
                "and the classifiers as concurrent processes"
                if "train" in stages
                else " (`--skip-train`: the evaluation of models trained before, each by "
                "`prg-train model=<family> experiment=converged`)"
            )
            + f"; fit CPU time (all threads) per family: {costs}; evaluation {_minutes(stages['evaluate']['seconds'])} wall at "
            f"K = {settings['k_marginal']} / {settings['k_conditional']} on {n_likelihood} test "
            f"samples for Table I and {n_test} for coherence and robustness. Coherence "
            f"classifiers {_accuracy_text(d['classifiers.json'])}.",
            "",
            table1_markdown(evaluate, models),
            "",
            coherence_markdown(evaluate),
            *(["", likeness] if (likeness := likeness_markdown(evaluate)) else []),
        ]
    )


def _accuracy_text(classifiers: dict) -> str:
    return "test accuracy " + ", ".join(
        f"{name} {classifiers[name]['test_accuracy']:.1%}" for name in ("traj", "image")
    )
