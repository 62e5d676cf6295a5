"""One results table from the benchmark and demo-report JSON: ``benchmarks/results.md`` and the
README's generated blocks (numbers are never typed by hand).

    python benchmarks/summarize.py              # results.md + README blocks from the committed JSON
    python benchmarks/summarize.py --snapshot   # first copy the demo's report JSON (after `make demo`)
                                                # into benchmarks/results/demo/
    python benchmarks/summarize.py --snapshot-converged converged   # after `make converged`
    python benchmarks/summarize.py --check      # exit 1 if results.md or the README are stale

Inputs: ``benchmarks/results/bench_*.json`` (written by each benchmark) and
``benchmarks/results/demo/*.json`` (a snapshot of the DVC pipeline's metrics, with the
``dvc.lock`` hashes of the outputs they came from). Every benchmark figure is shown next to the
reference it was measured against in the same run, with the ratio ours / reference.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
DEMO = RESULTS / "demo"
CONVERGED = RESULTS / "converged"
SUMMARY = ROOT / "benchmarks" / "results.md"
README = ROOT / "README.md"

# each model's and the classifiers' metrics, relative to the folder that holds ``models/``
MODEL_SOURCES = {
    "models_cvae.json": "models/cvae/metrics.json",
    "models_avae_ts.json": "models/avae_ts/metrics.json",
    "models_avae_ti.json": "models/avae_ti/metrics.json",
    "models_muse.json": "models/muse/metrics.json",
    "classifiers.json": "models/classifiers/metrics.json",
    "evaluate.json": "reports/metrics.json",
}
# DVC outputs copied by --snapshot: snapshot name -> path in the repository after `make demo`
DEMO_SOURCES = {
    "prepare.json": "reports/prepare/synthetic/metrics.json",
    **MODEL_SOURCES,
    "dictaphone.json": "reports/dictaphone/metrics.json",
    "simulate.json": "reports/simulate/metrics.json",
    "study.json": "reports/study/readability/metrics.json",
}
# outputs of `make converged` copied by --snapshot-converged: snapshot name -> path under its root
CONVERGED_SOURCES = {**MODEL_SOURCES, "run.json": "reports/paper_scale.json"}
FAMILIES = {
    "cvae": "PRG_CVAE(T,S)",
    "avae_ts": "PRG_AVAE(T,S)",
    "avae_ti": "PRG_AVAE(T,I)",
    "muse": "PRG_MUSE(T,S,I)",
}


class SummaryError(Exception):
    """A results file that is missing or does not have the expected fields."""


@dataclass(frozen=True)
class Row:
    figure: str
    ours: str
    reference: str
    reference_value: str
    ratio: float  # ours / reference
    target: str = ""


# ---------------------------------------------------------------- benchmark adapters


def _prepare(d: dict) -> list[Row]:
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


def _train(d: dict) -> list[Row]:
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


def _evaluate(d: dict) -> list[Row]:
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


def _dmp(d: dict) -> list[Row]:
    target = f"<= {1 / d['settings']['target_ratio']:.2g}"
    rows = []
    for r in d["rows"]:
        ours = r["ours_fit_ms"] + r["ours_rollout_ms"]
        theirs = r["theirs_fit_ms"] + r["theirs_rollout_ms"]
        rows.append(
            Row(
                f"DMP fit + rollout, {r['points']} points, {r['basis']} bases",
                f"{ours:.1f} ms (RMSE {10 * r['ours_rmse_cm']:.2g} mm)",
                "movement-primitives",
                f"{theirs:.1f} ms (RMSE {10 * r['theirs_rmse_cm']:.2g} mm)",
                ours / theirs,
                target,
            )
        )
    for r in d["equal_error"]:
        rows.append(
            Row(
                f"DMP at equal error, {r['points']} points",
                f"{r['ours_ms']:.1f} ms ({r['ours_basis']} bases)",
                "movement-primitives",
                f"{r['theirs_ms']:.1f} ms ({r['theirs_basis']} bases)",
                r["ours_ms"] / r["theirs_ms"],
                target,
            )
        )
    return rows


def _lasa(d: dict) -> list[Row]:
    speed = f"<= {1 / d['settings']['target_ratio']:.2g}"
    rows = []
    for r in d["rows"]:
        rows.append(
            Row(
                f"DMP on LASA, {r['demos']} human demonstrations, {r['basis']} bases: "
                "fit + rollout (median)",
                f"{r['ours_ms']:.1f} ms",
                "movement-primitives",
                f"{r['theirs_ms']:.1f} ms",
                r["ours_ms"] / r["theirs_ms"],
                speed,
            )
        )
        for kind in ("median", "worst"):
            rows.append(
                Row(
                    f"DMP on LASA, {r['basis']} bases: RMSE {kind} (at rest: "
                    f"{r[f'rest_rmse_{kind}_mm']:.3g} mm)",
                    f"{r[f'ours_rmse_{kind}_mm']:.3g} mm",
                    "movement-primitives",
                    f"{r[f'theirs_rmse_{kind}_mm']:.3g} mm",
                    r[f"ours_rmse_{kind}_mm"] / r[f"theirs_rmse_{kind}_mm"],
                    f"<= 1 on every demonstration ({r['demos'] - len(r['ours_worse_than_theirs'])}"
                    f" of {r['demos']})"
                    if kind == "worst"
                    else "",
                )
            )
    return rows


def _write_word(d: dict) -> list[Row]:
    target_ms = d["settings"]["target_ms_6_letters"]
    rows = [
        Row(
            f"write a {r['letters']}-letter word, {r['family']} (label -> DMP rollout)",
            f"{r['total_ms']:.1f} ms",
            "straight-line joiner",
            f"{r['straight_ms']:.1f} ms",
            r["total_ms"] / r["straight_ms"],
            f"<= {target_ms:.0f} ms" if r["letters"] == 6 else "",
        )
        for r in d["rows"]
        if r["letters"] in (1, 6, 12)
    ]
    worst = max(r["max_rmse_mm"] for r in d["rows"])
    target_mm = d["settings"]["target_rmse_mm"]
    rows.append(
        Row(
            "DMP reproduction error, worst word",
            f"{worst:.3f} mm",
            "target",
            f"{target_mm} mm",
            worst / target_mm,
            "<= 1",
        )
    )
    target_ratio = d["settings"].get("target_speech_ratio")
    for r in d.get("speech", []):
        if "ratio" in r:  # end to end in a warm writer, against recognise() alone
            rows.append(
                Row(
                    f"speech -> DMP rollout, warm Writer, {r['backend']}, '{r['word']}' "
                    + ("(nothing heard)" if r["heard"] is None else f"(heard '{r['heard']}')"),
                    f"{r['total_ms']:.0f} ms",
                    "recognise() alone",
                    f"{r['recognise_ms']:.0f} ms",
                    r["ratio"],
                    f"<= {target_ratio}",
                )
            )
    return rows


# issue "Speech a robot can rely on": with a lexicon, this accuracy at no more than free
# transcription's median latency (latency ratio <= 1)
SPEECH_TARGETS = {
    ("whisper+rescore", "clean"): ">= 98%, latency <= 1x",
    ("whisper+rescore", "hard"): ">= 95%, latency <= 1x",
}


def _speech(d: dict) -> list[Row]:
    reference = d["settings"]["reference"]
    words = d["settings"]["words"]
    said = f"{len(words)} words: {', '.join(words[:3])}, ..."
    rows = []
    for condition, setting in d["settings"]["conditions"].items():
        ref = d["summary"][reference][condition]
        noise = "" if setting["snr_db"] is None else f", noise {setting['snr_db']:g} dB SNR"
        for name, summary in d["summary"].items():
            if name == reference:
                continue
            s = summary[condition]
            accuracy = f"{s['accuracy']:.1%}"
            if s.get("answered", 1) < 1:  # min_lead: asked again for the rest
                answered = s["accuracy_answered"] or 0.0
                accuracy += f", {answered:.1%} of the {s['answered']:.1%} answered"
            rows.append(
                Row(
                    f"speech, {condition} ({said}; {', '.join(setting['voices'])}{noise}), {name} "
                    "(exact word; median latency, latency ratio)",
                    f"{accuracy} ({s['median_ms']:,.0f} ms, {s['latency_ratio']:.2f}x)",
                    f"{reference} alone",
                    f"{ref['accuracy']:.1%} ({ref['median_ms']:,.0f} ms)",
                    s["accuracy"] / ref["accuracy"] if ref["accuracy"] else math.nan,
                    SPEECH_TARGETS.get((name, condition), ""),
                )
            )
    return rows


def _simulate(d: dict) -> list[Row]:
    rows = []
    for r in d["rows"]:
        rows.append(
            Row(
                f"pen tracking error, {r['robot']}, '{r['word']}' (real-time factor "
                f"{r['realtime_factor']:.0f})",
                f"{1000 * r['tracking_mean_mm']:.1f} um",
                "plain PyBullet IK",
                f"{1000 * r['plain_tracking_mean_mm']:.1f} um",
                r["tracking_mean_mm"] / r["plain_tracking_mean_mm"],
            )
        )
    for robot in dict.fromkeys(r["robot"] for r in d["rows"]):
        r = max((r for r in d["rows"] if r["robot"] == robot), key=lambda r: r["letters"])
        rows.append(
            Row(
                f"IK error, {robot}, '{r['word']}'",
                f"{1000 * r['ik_error_mean_mm']:.2f} um",
                "null-space PyBullet IK alone",
                f"{1000 * r['null_space_ik_error_mean_mm']:,.0f} um",
                r["ik_error_mean_mm"] / r["null_space_ik_error_mean_mm"],
            )
        )
    return rows


def _connections(d: dict) -> list[Row]:
    rows = []
    reference = {r["decoding"]: r for r in d["rows"] if r["method"] == "alg1"}
    for r in d["rows"]:
        if r["method"] != "hand":
            continue
        ref = reference[r["decoding"]]
        rows.append(
            Row(
                f"connections cutting a letter's ink, {r['words']} words ({r['decoding']} letters)",
                f"{r['crossing']}/{r['connections']} ({r['crossing_share']:.0%})",
                "the paper's Algorithm 1",
                f"{ref['crossing']}/{ref['connections']} ({ref['crossing_share']:.0%})",
                max(r["crossing"], 0.5) / max(ref["crossing"], 0.5),
                "<= 10 %",
            )
        )
        rows.append(
            Row(
                f"compose a word (layout, connections, DMP), {r['decoding']} letters",
                f"{r['compose_ms_median']:.1f} ms",
                "the paper's Algorithm 1",
                f"{ref['compose_ms_median']:.1f} ms",
                r["compose_ms_median"] / ref["compose_ms_median"],
            )
        )
    return rows


def _kinematics(d: dict) -> list[Row]:
    table = d["table"]
    lasa, executed = table["LASA (human)"], table["human: executed"]
    paper = table["constant: executed"]
    noise = table["control: white noise"]
    targets = d["settings"]["targets"]
    names = {
        "beta": "speed-curvature power law beta",
        "speed_cv": "speed coefficient of variation",
        "lognormal_snr_db": "sigma-lognormal fit SNR (dB)",
    }
    rows = []
    for key, name in names.items():
        low, high = targets[key]
        rows.append(
            Row(
                f"{name}, executed pen tip, {len(d['settings']['words'])} words (the paper's "
                f"constant speed {paper[key]['median']:.2f}; white noise {noise[key]['median']:.2f})",
                f"{executed[key]['median']:.3f}",
                "LASA human demonstrations",
                f"{lasa[key]['median']:.3f}",
                executed[key]["median"] / lasa[key]["median"],
                f">= {low:g}" + (f", <= {high:g}" if high is not None else ""),
            )
        )
    return rows


def _startup(d: dict) -> list[Row]:
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


BENCHMARKS: dict[str, Callable[[dict], list[Row]]] = {
    "bench_prepare": _prepare,
    "bench_train": _train,
    "bench_evaluate": _evaluate,
    "bench_dmp": _dmp,
    "bench_lasa": _lasa,
    "bench_write": _write_word,
    "bench_connections": _connections,
    "bench_kinematics": _kinematics,
    "bench_speech": _speech,
    "bench_speech_other_voices": _speech,
    "bench_speech_other_words": _speech,
    "bench_simulate": _simulate,
    "bench_startup": _startup,
}


def read_json(path: Path) -> dict:
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise SummaryError(f"{path}: missing (run its benchmark or `make demo`)") from None
    except (OSError, ValueError) as err:
        raise SummaryError(f"{path}: not readable JSON ({err})") from None


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


def _ratio(value: float) -> str:
    if math.isnan(value):
        return "-"
    if not math.isfinite(value):
        return str(value)
    if value == 0 or 0.01 <= abs(value) < 1000:
        return f"{value:.3g}"
    return f"{value:.1e}"


def _table(header: list[str], body: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cells) + " |" for cells in body]
    return "\n".join(lines)


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
    rows = benchmark_rows(results)
    body = [
        [name, r.figure, r.ours, r.reference, r.reference_value, _ratio(r.ratio), r.target]
        for name, items in rows.items()
        for r in items
    ]
    header = ["benchmark", "figure", "ours", "reference", "reference value", "ratio", "target"]
    return (
        "Ratio = ours / reference, both measured in the same run (`make bench`; JSON in "
        "`benchmarks/results/`). Times: lower is better; throughput and accuracy: higher.\n\n"
        + _table(header, body)
        + paper_cost_markdown(results)
    )


# ---------------------------------------------------------------- demo reports


def _copy_json(source: Path, target: Path) -> None:
    """Copy a JSON file that reads as JSON, through a temporary name."""
    read_json(source)
    tmp = target.with_name(f".{target.name}.tmp")
    shutil.copyfile(source, tmp)
    os.replace(tmp, target)


def snapshot(root: Path = ROOT, demo: Path = DEMO) -> None:
    """Copy the demo pipeline's metrics JSON into ``demo`` with their ``dvc.lock`` hashes."""
    import yaml

    lock = yaml.safe_load((root / "dvc.lock").read_text())
    hashes = {
        out["path"]: out.get("md5", "")
        for stage in lock["stages"].values()
        for out in stage.get("outs", [])
    }
    demo.mkdir(parents=True, exist_ok=True)
    provenance = {}
    for name, source in DEMO_SOURCES.items():
        _copy_json(root / source, demo / name)
        # the lock entry of the file itself, or of the output folder holding it
        owner = max(
            (out for out in hashes if source == out or source.startswith(out + "/")),
            key=len,
            default=None,
        )
        provenance[name] = {"source": source, "dvc_out": owner, "dvc_md5": hashes.get(owner)}
    _write_file(demo / "provenance.json", json.dumps(provenance, indent=2, sort_keys=True) + "\n")


def snapshot_converged(source: Path, converged: Path = CONVERGED) -> None:
    """Copy the metrics of a finished ``make converged`` (its ``--root``) into ``converged``."""
    run = read_json(source / CONVERGED_SOURCES["run.json"])
    if run.get("status") != "ok" or run.get("profile") != "converged":
        raise SummaryError(
            f"{source / CONVERGED_SOURCES['run.json']}: not a finished converged run "
            f"(profile {run.get('profile')!r}, status {run.get('status')!r})"
        )
    converged.mkdir(parents=True, exist_ok=True)
    for name, relative in CONVERGED_SOURCES.items():
        _copy_json(source / relative, converged / name)


TABLE1_CELLS = ["T", "S", "I", "T_given_S", "T_given_I", "S_given_T", "I_given_T"]
TRAJ_CELLS = [c for c in TABLE1_CELLS if c.startswith("T")]  # trajectory targets
MODEL_STD = "_model_std"  # prg.evaluation.likelihood.MODEL_STD_SUFFIX
COHERENCE_CELLS = [
    "T_given_S",
    "T_given_I",
    "T_given_SI",
    "I_given_T",
    "S_given_T",
    "I_given_S",
    "T_given_T",
]
# trajectory coherence from every subset of inputs (missing-modality robustness)
ROBUSTNESS_SUBSETS = ["S", "I", "SI", "T", "TS", "TI", "TSI"]
ROUGHNESS_CELLS = ["T_given_S", "T_given_I"]
TEST_ROUGHNESS = "test_split/roughness"


def _cell_title(cell: str) -> str:
    return "log p(x_" + cell.replace("_given_", " \\| x_") + ")"


def _number(evaluate: dict, key: str, fmt: str) -> str:
    """A metric formatted, or '-' when the snapshot does not hold it."""
    value = evaluate.get(key)
    return "-" if value is None else format(value, fmt)


def _legacy_table1(evaluate: dict) -> bool:
    """A snapshot written before Table I had two trajectory conventions: its ``logp_T*`` values
    are under the models' own std (0.1), not the unit-variance main table's."""
    return any("/logp_" in k for k in evaluate) and not any(k.endswith(MODEL_STD) for k in evaluate)


def table1_markdown(evaluate: dict, models: dict[str, dict]) -> str:
    """Table I in the paper's convention (unit-variance trajectory Gaussian, the paper's values
    in parentheses) and the trajectory cells under each model's own std."""
    from prg.evaluation.likelihood import PAPER_TABLE1

    legacy = _legacy_table1(evaluate)

    def main_cell(family: str, cell: str) -> str:
        if legacy and cell in TRAJ_CELLS:
            return "-"
        ours = _number(evaluate, f"{family}/logp_{cell}", ".1f")
        paper = PAPER_TABLE1.get(family, {}).get(f"logp_{cell}")
        return ours if ours == "-" or paper is None else f"{ours} ({paper:.2f})"

    def own_cell(family: str, cell: str) -> str:
        key = f"{family}/logp_{cell}" + ("" if legacy else MODEL_STD)
        return _number(evaluate, key, ".1f")

    main = _table(
        ["model", *map(_cell_title, TABLE1_CELLS), "val loss"],
        [
            [
                FAMILIES[family],
                *(main_cell(family, c) for c in TABLE1_CELLS),
                _number(models.get(family, {}), "val_loss", ".1f"),
            ]
            for family in FAMILIES
        ],
    )
    own = _table(
        ["model", *map(_cell_title, TRAJ_CELLS)],
        [[FAMILIES[family], *(own_cell(family, c) for c in TRAJ_CELLS)] for family in FAMILIES],
    )
    lines = [
        "**Table I** (importance-weighted log-likelihoods, nats; higher is better) in the "
        "paper's convention: trajectory cells under a unit-variance Gaussian with its "
        "normalising constant, the paper's values in parentheses (its label and image terms "
        "follow another convention, see *Evaluation*); and the validation loss of each model:",
        "",
        main,
        "",
        "The trajectory cells under each model's own std (0.1, the one it is trained with), "
        "from the same importance samples:",
        "",
        own,
    ]
    if legacy:
        lines[1:1] = [
            "",
            "(This snapshot predates the unit-variance table, so its trajectory cells appear "
            "only in the second table; `make demo` then `python benchmarks/summarize.py "
            "--snapshot` refresh it.)",
        ]
    return "\n".join(lines)


def coherence_markdown(evaluate: dict) -> str:
    """Exact and shape-twin-folded coherence, and the roughness ratios of decoded letters."""

    def variants(family: str) -> list[tuple[str, str]]:
        """(row title, key infix) of the family's generation kinds shown: the paper's posterior
        mean, and the imputed one where the snapshot has it."""
        rows = [(FAMILIES[family], "")]
        if any(k.startswith(f"{family}/coherence_imputed_") for k in evaluate):
            rows.append((f"{FAMILIES[family]}, imputed", "imputed_"))
        return rows

    def cell(family: str, kind: str, c: str) -> str:
        exact = _number(evaluate, f"{family}/coherence_{kind}{c}", ".0%")
        folded = _number(evaluate, f"{family}/coherence_folded_{kind}{c}", ".0%")
        return "-" if exact == folded == "-" else f"{exact} / {folded}"

    coherence = _table(
        ["model", *(c.replace("_given_", " from ") for c in COHERENCE_CELLS)],
        [
            [title, *(cell(f, kind, c) for c in COHERENCE_CELLS)]
            for f in FAMILIES
            for title, kind in variants(f)
        ],
    )
    roughness = _table(
        ["model", *(c.replace("_given_", " from ") for c in ROUGHNESS_CELLS)],
        [
            [
                title,
                *(
                    _number(evaluate, f"{f}/roughness_ratio_{kind}{c}", ".2f")
                    for c in ROUGHNESS_CELLS
                ),
            ]
            for f in FAMILIES
            for title, kind in variants(f)
        ],
    )
    robustness = _table(
        ["model", *(f"{{{','.join(subset)}}}" for subset in ROBUSTNESS_SUBSETS)],
        [
            [
                title,
                *(
                    _number(evaluate, f"{f}/coherence_folded_{kind}T_given_{subset}", ".0%")
                    for subset in ROBUSTNESS_SUBSETS
                ),
            ]
            for f in FAMILIES
            for title, kind in variants(f)
        ],
    )
    shifted = _shifted_images_markdown(evaluate)
    return "\n".join(
        [
            "**Cross-modal coherence** (the generated modality classified as the given label; "
            "exact / with shape twins such as o/O/0 counted right; posterior mean, and for "
            "MUSE also *imputed*: after 20 rounds of imputing the missing modalities, as "
            "`prg-write` decodes):",
            "",
            coherence,
            "",
            "**Missing-modality robustness**: trajectory coherence (folded) from each subset of "
            "inputs a model accepts ('-' where it cannot take it; subsets with T are "
            "reconstructions):",
            "",
            robustness,
            "",
            *shifted,
            "**Smoothness**: roughness ratio of the letters decoded from labels or images "
            "(posterior mean): their median roughness over the test letters' median roughness "
            f"({_number(evaluate, TEST_ROUGHNESS, '.3f')}); 1 is as smooth as the data, the "
            "target is <= 2:",
            "",
            roughness,
        ]
    )


def _shifted_images_markdown(evaluate: dict) -> list[str]:
    """Coherence from test images moved off-centre (lines, then a blank one; none for a snapshot
    made before the evaluation had it)."""
    shifts = sorted(
        {
            int(k.rsplit("_shift", 1)[1])
            for k in evaluate
            if "/coherence_folded_T_given_I_shift" in k
        }
    )
    if not shifts:
        return []
    cells = [(c, s) for c in ("T_given_I", "S_given_I") for s in shifts]
    table = _table(
        [
            "model",
            *(
                f"{c.replace('_given_', ' from ')}, " + (f"<= {s} px" if s else "as is")
                for c, s in cells
            ),
        ],
        [
            [
                FAMILIES[f],
                *(_number(evaluate, f"{f}/coherence_folded_{c}_shift{s}", ".0%") for c, s in cells),
            ]
            for f in FAMILIES
            if f"{f}/coherence_folded_T_given_I_shift0" in evaluate
        ],
    )
    return [
        "**Images moved off-centre**: coherence (folded) of what a model generates from a test "
        "image alone, as rendered and moved by a random offset of up to 1 or 2 pixels per axis "
        "(`robustness.md`):",
        "",
        table,
        "",
    ]


LIKENESS_MEASURES = ("legible", "precision", "recall", "c2st", "spread")


def likeness_markdown(evaluate: dict) -> str:
    """The likeness table (``<family>/likeness_<mode>_<measure>``) and the style rates
    (``<family>/style_k<k>_generated`` ...), where the snapshot has them (older ones do not)."""
    pattern = re.compile(r"^([^/]+)/likeness_(.+)_legible$")
    rows = [m.groups() for k in evaluate if (m := pattern.match(k))]
    if not rows:
        return ""
    families = ["real", *list(FAMILIES)]
    modes = ["val_writers", "train_originals", "mean", "imputed", "sampled_t0.5", "sampled_t1"]
    modes += ["hand_t0", "hand", "hand_t1"]
    rows.sort(key=lambda r: (families.index(r[0]), modes.index(r[1]) if r[1] in modes else 99))
    body = []
    for family, mode in rows:
        name = "real letters" if family == "real" else family
        shown = mode.replace("_", " ").replace(" t", " T=")
        if mode == "hand":
            shown = "**hand (default)**"
        elif mode == "mean":
            shown = "mean (the paper)"
        cells = [f"{evaluate[f'{family}/likeness_{mode}_{m}']:.2f}" for m in LIKENESS_MEASURES]
        body.append([name, shown, *cells])
    lines = [
        "**Likeness to held-out writers** (`reports/likeness.md`): 10 letters per class from "
        "their labels against the test split's letters; legible = read right by the trajectory "
        "classifier (folded); k-NN precision / recall (k = 3); C2ST = linear classifier's "
        "accuracy telling them from real (0.5 ideal); spread = within-class distance over the "
        "real letters' (1 ideal). The first rows are real letters scored the same way.",
        "",
        _table(["family", "mode", *LIKENESS_MEASURES], body),
    ]
    style = re.compile(r"^([^/]+)/style_k(\d+)_generated$")
    found = [m.groups() for k in evaluate if (m := style.match(k))]
    found.sort(key=lambda r: (list(FAMILIES).index(r[0]) if r[0] in FAMILIES else 99, int(r[1])))
    if found:
        lines += [
            "",
            "**A writer's style from k letters** (`reports/styles.md`): share of letters written "
            "in a held-out writer's style that a writer-identification classifier attributes to "
            "that writer, over the same for the writer's own letters (ratio).",
            "",
            _table(
                ["family", "k", "generated", "own letters", "ratio"],
                [
                    [
                        f,
                        k,
                        f"{evaluate[f'{f}/style_k{k}_generated']:.2f}",
                        f"{evaluate[f'{f}/style_real']:.2f}",
                        f"{evaluate[f'{f}/style_k{k}_ratio']:.2f}",
                    ]
                    for f, k in found
                ],
            ),
        ]
    return "\n".join(lines)


def demo_markdown(demo: Path = DEMO) -> str:
    """Tables of the demo pipeline's results (quick profile, synthetic data)."""
    d = {name: read_json(demo / name) for name in DEMO_SOURCES}
    evaluate = d["evaluate.json"]
    models = {family: d[f"models_{family}.json"] for family in FAMILIES}
    dictaphone = d["dictaphone.json"]
    table2 = _table(
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
    lines = [
        f"Synthetic data: {prepare['train_samples']:,} / {prepare['val_samples']:,} / "
        f"{prepare['test_samples']:,} train / val / test samples; coherence classifiers "
        f"{_accuracy_text(classifiers)}.",
        "",
        table1_markdown(evaluate, models),
        "",
        coherence_markdown(evaluate),
        "",
        *([likeness_markdown(evaluate), ""] if likeness_markdown(evaluate) else []),
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
    models = {family: d[f"models_{family}.json"] for family in FAMILIES}
    settings, stages = run["settings"], run["stages"]
    fit = run.get("fit", {})
    costs = ", ".join(
        f"{FAMILIES[f]} {_minutes(fit[f]['fit_cpu_s'])} CPU ({fit[f]['epochs']:.0f} epochs)"
        for f in FAMILIES
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
        ]
    )


def _accuracy_text(classifiers: dict) -> str:
    return "test accuracy " + ", ".join(
        f"{name} {classifiers[name]['test_accuracy']:.1%}" for name in ("traj", "image")
    )


# ---------------------------------------------------------------- outputs


def _write_file(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


def results_markdown(
    results: Path = RESULTS, demo: Path = DEMO, converged: Path = CONVERGED
) -> str:
    return (
        "# Benchmark results\n\n"
        "Generated by `python benchmarks/summarize.py` (run by `make bench`); do not edit.\n\n"
        + benchmarks_markdown(results)
        + "\n\n## The demo pipeline\n\n"
        + "`make demo` (quick profile, synthetic data), from the snapshot in "
        + "`benchmarks/results/demo/`.\n\n"
        + demo_markdown(demo)
        + "\n\n## The converged profile\n\n"
        + "`make converged` (`experiment=converged`, synthetic data), from the snapshot in "
        + "`benchmarks/results/converged/`.\n\n"
        + converged_markdown(converged)
        + "\n"
    )


def fill_block(text: str, name: str, content: str) -> str:
    """Replace what lies between ``<!-- generated:NAME -->`` and ``<!-- end:NAME -->``."""
    begin, end = f"<!-- generated:{name} -->", f"<!-- end:{name} -->"
    start, stop = text.find(begin), text.find(end)
    if start < 0 or stop < start:
        raise SummaryError(f"README.md: no {begin} ... {end} block")
    return text[: start + len(begin)] + "\n" + content + "\n" + text[stop:]


def readme_text(
    readme: str, results: Path = RESULTS, demo: Path = DEMO, converged: Path = CONVERGED
) -> str:
    readme = fill_block(readme, "benchmarks", benchmarks_markdown(results))
    readme = fill_block(readme, "demo", demo_markdown(demo))
    return fill_block(readme, "converged", converged_markdown(converged))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--snapshot", action="store_true", help="copy the demo's metrics first")
    parser.add_argument(
        "--snapshot-converged",
        type=Path,
        metavar="ROOT",
        help="copy the metrics of a finished `make converged` under ROOT first",
    )
    parser.add_argument("--check", action="store_true", help="exit 1 if any output is stale")
    args = parser.parse_args(argv)
    try:
        if args.snapshot:
            snapshot()
        if args.snapshot_converged:
            snapshot_converged(args.snapshot_converged)
        outputs = {
            SUMMARY: results_markdown(),
            README: readme_text(README.read_text()),
        }
    except SummaryError as err:
        print(f"summarize: error: {err}", file=sys.stderr)
        return 2
    stale = [p for p, text in outputs.items() if not p.is_file() or p.read_text() != text]
    if args.check:
        for path in stale:
            print(
                f"summarize: {path.relative_to(ROOT)} is stale: run `make results`", file=sys.stderr
            )
        return 1 if stale else 0
    for path in stale:
        _write_file(path, outputs[path])
        print(f"wrote {path.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
