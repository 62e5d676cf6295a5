"""Benchmark the simulated writing robot: tracking error and real-time factor, both arms.

For words of 1, 4 and 8 letters, each arm (Panda, iiwa) writes the word with the default
settings of ``conf/simulate.yaml`` (PyBullet DIRECT, 240 Hz physics, 60 Hz IK waypoints,
null-space IK refined by a plain solve). Reported per run:

- tracking error mean / max (mm) between the commanded pen-down path and the ink, the longest
  ink gap and the pen step (mm);
- simulated time / wall time (the real-time factor) of the whole run (IK + physics), and of
  the physics loop alone;

and, side by side in the same run on the same words, the two IK references: the null-space
solve alone (``ik.method=null_space``, PyBullet's IK with rest pose and limits, as usually
used) and the plain solve alone (``ik.method=plain``, seeded with the previous solution, no
posture control). Their tracking error is given as a ratio to the default's (reference /
refined: how many times larger the reference's error is).

Words: the demo MUSE model's (``models/muse/model.ckpt``, as ``prg-write`` writes them) when it
exists, else the same words in a Hershey font (:func:`prg.sim.font_word`).

Usage: ``python benchmarks/bench_simulate.py [--robots panda iiwa] [--words a wave drawings]``
Prints a table and writes ``benchmarks/results/bench_simulate.json``.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from dataclasses import replace
from pathlib import Path

from prg.commands.cli import compose_config
from prg.commands.settings import simulation_settings
from prg.files import write_json
from prg.pipeline.word import WordTrajectory
from prg.sim import font_word, simulate_word

RESULTS = Path(__file__).parent / "results"
ROOT = Path(__file__).parent.parent
WORDS = ("a", "wave", "drawings")  # 1, 4 and 8 letters
REFERENCES = ("null_space", "plain")
TOLERANCE_MM = 20.0  # let the references' IK miss by millimetres instead of refusing


def make_words(words: list[str]) -> tuple[dict[str, WordTrajectory], str]:
    """The words from the demo MUSE model, or from a Hershey font; and their source."""
    ckpt = ROOT / "models" / "muse" / "model.ckpt"
    if not ckpt.exists():
        return {w: font_word(w) for w in words}, "Hershey font (futural), no models/muse"
    from prg.commands.settings import generate_settings
    from prg.writer import Writer

    writer = Writer.from_checkpoint(ckpt, settings=generate_settings(compose_config("write", [])))
    out = {w: writer.write(text=w).word for w in words}
    return out, str(ckpt.relative_to(ROOT))


def run(word: WordTrajectory, robot_name: str, method: str) -> dict:
    robot, settings = simulation_settings(compose_config("simulate", [f"robot={robot_name}"]))
    if method != "refined":
        settings = replace(
            settings, ik=replace(settings.ik, method=method, tolerance_mm=TOLERANCE_MM)
        )
    start = time.perf_counter()
    result = simulate_word(word, robot, settings, render=False)
    total = time.perf_counter() - start
    m = dict(result.metrics)
    m["total_wall_s"] = total
    m["realtime_factor_total"] = m["sim_s"] / total
    m["realtime_factor_physics"] = m["sim_s"] / m["wall_s"]
    m["method"] = method
    return m


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--robots", nargs="+", default=["panda", "iiwa"])
    parser.add_argument("--words", nargs="+", default=list(WORDS))
    parser.add_argument("--no-references", action="store_true", help="only the default IK")
    args = parser.parse_args()

    words, source = make_words(args.words)
    methods = ["refined"] if args.no_references else ["refined", *REFERENCES]
    rows = []
    for robot in args.robots:
        for text, word in words.items():
            runs = {method: run(word, robot, method) for method in methods}
            best = runs["refined"]
            row = {
                "robot": robot,
                "word": text,
                "letters": len(text),
                "width_cm": best["word_width_cm"],
                "writing_s": best["writing_s"],
                "sim_s": best["sim_s"],
                "tracking_mean_mm": best["tracking_error_mean_mm"],
                "tracking_max_mm": best["tracking_error_max_mm"],
                "max_ink_gap_mm": best["max_ink_gap_mm"],
                "pen_step_mm": best["pen_step_mm"],
                "wall_s": best["total_wall_s"],
                "ik_wall_s": best["ik_wall_s"],
                "physics_wall_s": best["wall_s"],
                "realtime_factor": best["realtime_factor_total"],
                "realtime_factor_physics": best["realtime_factor_physics"],
                "ik_error_mean_mm": best["ik_error_mean_mm"],
                "rest_distance_max_rad": best["rest_distance_max_rad"],
            }
            for method in methods[1:]:
                ref = runs[method]
                row[f"{method}_tracking_mean_mm"] = ref["tracking_error_mean_mm"]
                row[f"{method}_tracking_max_mm"] = ref["tracking_error_max_mm"]
                row[f"{method}_ratio"] = (
                    ref["tracking_error_mean_mm"] / best["tracking_error_mean_mm"]
                )
                row[f"{method}_realtime_factor"] = ref["realtime_factor_total"]
                row[f"{method}_ik_error_mean_mm"] = ref["ik_error_mean_mm"]
                row[f"{method}_ik_error_ratio"] = ref["ik_error_mean_mm"] / best["ik_error_mean_mm"]
                row[f"{method}_rest_distance_max_rad"] = ref["rest_distance_max_rad"]
                row[f"{method}_ink_strokes"] = ref["ink_strokes"]
            rows.append(row)
            print(f"  {robot:6s} {text!r}: done", flush=True)

    header = (
        f"{'robot':6s} {'word':10s} {'cm':>5s} {'sim s':>6s} {'mean mm':>8s} {'max mm':>7s} "
        f"{'gap mm':>7s} {'step mm':>7s} {'wall s':>7s} {'RTF':>5s} {'RTF phys':>8s}"
    )
    print(f"\nwords: {source}\n{header}")
    for r in rows:
        line = (
            f"{r['robot']:6s} {r['word']:10s} {r['width_cm']:5.1f} {r['sim_s']:6.1f} "
            f"{r['tracking_mean_mm']:8.4f} {r['tracking_max_mm']:7.4f} {r['max_ink_gap_mm']:7.3f} "
            f"{r['pen_step_mm']:7.3f} {r['wall_s']:7.2f} {r['realtime_factor']:5.1f} "
            f"{r['realtime_factor_physics']:8.1f}"
        )
        print(line)
    if not args.no_references:
        print(
            "\nreferences (ratio = reference / refined; 'no ink': the tip never came within the "
            "contact band)\n"
            f"{'robot':6s} {'word':10s} {'method':10s} {'mean mm':>8s} {'ratio':>7s} "
            f"{'IK err mm':>10s} {'ratio':>7s} {'max |q-rest|':>12s}"
        )
        for r in rows:
            print(
                f"{r['robot']:6s} {r['word']:10s} {'refined':10s} {r['tracking_mean_mm']:8.4f} "
                f"{1.0:7.1f} {r['ik_error_mean_mm']:10.5f} {1.0:7.1f} "
                f"{r['rest_distance_max_rad']:12.3f}"
            )
            for method in REFERENCES:
                mean = r[f"{method}_tracking_mean_mm"]
                shown = (
                    f"{mean:8.4f} {r[f'{method}_ratio']:7.1f}" if mean < 1e9 else f"{'no ink':>16s}"
                )
                print(
                    f"{'':6s} {'':10s} {method:10s} {shown} "
                    f"{r[f'{method}_ik_error_mean_mm']:10.5f} {r[f'{method}_ik_error_ratio']:7.0f} "
                    f"{r[f'{method}_rest_distance_max_rad']:12.3f}"
                )

    RESULTS.mkdir(exist_ok=True)
    out = RESULTS / "bench_simulate.json"
    write_json(
        out,
        {
            "benchmark": "bench_simulate",
            "words_from": source,
            "settings": "conf/simulate.yaml defaults (240 Hz physics, 60 Hz IK waypoints)",
            "references": {
                "null_space": "PyBullet IK with rest pose and limits alone",
                "plain": "PyBullet IK alone, seeded with the previous solution",
                "ratio": "reference tracking mean / refined tracking mean",
            },
            "machine": {
                "platform": platform.platform(),
                "cpus": os.cpu_count(),
                "python": platform.python_version(),
            },
            "rows": rows,
        },
    )
    print(f"\nwrote {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
