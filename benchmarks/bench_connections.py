"""Benchmark connection strokes: how often they cut through a letter, and what they cost.

Over a fixed list of 66 everyday words (``WORDS``: the most frequent English words of three
letters or more, and the words the issue named), the demo model writes each word with every
connection method (``hand``, the default; ``alg1``, the paper's Algorithm 1 alone, the
reference; ``straight``) in both decodings (``hand``: letters in the hand of each word's seed;
``posterior``: the paper's posterior mean), and every connection is checked with
:func:`prg.pipeline.joins.ink_crossings` (a proper crossing of a letter's ink more than 1 mm from
the connection's ends). Reported per method and decoding: connections that cross, words with at
least one, connections that loop (cross themselves, :func:`prg.pipeline.joins.self_crossings`)
or swing above or below both letters they join by more than an arch's clearance
(:func:`prg.pipeline.joins.overshoot`), pen lifts between letters, the connections' length over
the straight distance, and the median time to compose a word (layout, connections, DMP), each
beside Algorithm 1's as a ratio. Target: at most 10 % of connections crossing ink with the
default method.

Usage: ``python benchmarks/bench_connections.py`` (needs ``models/muse/model.ckpt``: ``make
demo``). Prints a table and writes ``benchmarks/results/bench_connections.json``.
"""

from __future__ import annotations

import statistics
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
TARGET = 0.10
WORDS = [
    "the",
    "and",
    "you",
    "that",
    "was",
    "for",
    "are",
    "with",
    "his",
    "they",
    "one",
    "have",
    "this",
    "from",
    "word",
    "what",
    "some",
    "other",
    "were",
    "all",
    "there",
    "when",
    "your",
    "can",
    "said",
    "use",
    "each",
    "which",
    "she",
    "how",
    "their",
    "will",
    "way",
    "about",
    "many",
    "then",
    "them",
    "would",
    "write",
    "like",
    "these",
    "long",
    "make",
    "thing",
    "see",
    "him",
    "two",
    "has",
    "look",
    "more",
    "day",
    "could",
    "come",
    "did",
    "number",
    "sound",
    "most",
    "people",
    "over",
    "know",
    "water",
    "little",
    "letter",
    "joy",
    "moon",
    "dog",
]
METHODS = ("hand", "alg1", "straight")
DECODINGS = ("hand", "posterior")


def word_connections(word) -> list[tuple[np.ndarray, list[np.ndarray], tuple]]:
    """Each connection of a written word as its full path (from the end of one letter to the
    start of the next), with the word's letters and the two letters it joins."""
    kinds = word.segment_kinds
    inks = [word.segment_points(k) for k, kind in enumerate(kinds) if kind == "letter"]
    out = []
    for k, kind in enumerate(kinds):
        if kind == "connection":
            path = np.concatenate(
                [
                    word.segment_points(k - 1)[-1:],
                    word.segment_points(k),
                    word.segment_points(k + 1)[:1],
                ]
            )
            out.append((path, inks, (word.segment_points(k - 1), word.segment_points(k + 1))))
    return out


def measure(writer, words) -> dict:
    from prg.pipeline.joins import arch_clearance, ink_crossings, overshoot, self_crossings

    crossed = total = words_crossed = looped = swung = lifts = 0
    ratios, compose = [], []
    for i, text in enumerate(words):
        writer.settings = replace(writer.settings, seed=i)
        result = writer.write(text=text)
        compose.append(result.timings["compose"])
        lifts += result.word.segment_kinds.count("space")  # one word: every space is a lift
        hits = 0
        for path, inks, (prev, nxt) in word_connections(result.word):
            total += 1
            cut = ink_crossings(path, inks) > 0
            crossed += cut
            hits += cut
            looped += self_crossings(path) > 0
            distance = max(np.linalg.norm(path[-1] - path[0]), 1e-9)
            swung += overshoot(path, prev, nxt) > arch_clearance(distance)
            length = np.linalg.norm(np.diff(path, axis=0), axis=1).sum()
            ratios.append(length / distance)
        words_crossed += hits > 0
    return {
        "connections": total,
        "crossing": crossed,
        "crossing_share": crossed / total,
        "words": len(words),
        "words_crossing": words_crossed,
        "looping": looped,
        "leaving_band": swung,
        "pen_lifts": lifts,
        "length_ratio_median": float(np.median(ratios)),
        "compose_ms_median": 1000 * statistics.median(compose),
    }


def main() -> int:
    from prg.files import write_json
    from prg.models.checkpoint import load_model
    from prg.pipeline.compose import GenerateSettings
    from prg.writer import Writer

    ckpt = ROOT / "models" / "muse" / "model.ckpt"
    if not ckpt.is_file():
        print(f"bench_connections: {ckpt.relative_to(ROOT)} is missing: run `make demo` first")
        return 2
    model, info = load_model(ckpt)
    rows = []
    for decoding in DECODINGS:
        for method in METHODS:
            writer = Writer(
                model, GenerateSettings(mode=decoding, method=method), hands=info["hands"]
            )
            writer.write(text="warm")
            row = {"decoding": decoding, "method": method, **measure(writer, WORDS)}
            rows.append(row)
            print(
                f"{decoding:>9} {method:>8}: {row['crossing']}/{row['connections']} cross",
                flush=True,
            )
    reference = {r["decoding"]: r for r in rows if r["method"] == "alg1"}
    print(
        f"\nConnections cutting a letter's ink, {len(WORDS)} words (demo MUSE; ratios to the "
        "paper's Algorithm 1 in the same run; target <= 10 % with the default method)"
    )
    header = (
        f"{'decoding':>9} {'method':>8} | {'crossing':>9} {'share':>6} {'ratio':>6} | "
        f"{'words':>6} | {'loops':>5} {'band':>5} {'lifts':>5} | {'length':>7} | "
        f"{'compose ms':>10} {'ratio':>6}"
    )
    print(header)
    print("-" * len(header))
    for r in rows:
        ref = reference[r["decoding"]]
        r["crossing_ratio"] = r["crossing"] / max(ref["crossing"], 1)
        r["compose_ratio"] = r["compose_ms_median"] / ref["compose_ms_median"]
        flag = "  < target" if r["method"] == "hand" and r["crossing_share"] > TARGET else ""
        print(
            f"{r['decoding']:>9} {r['method']:>8} | {r['crossing']:>4}/{r['connections']:<4} "
            f"{r['crossing_share']:>6.0%} {r['crossing_ratio']:>6.2f} | {r['words_crossing']:>6} | "
            f"{r['looping']:>5} {r['leaving_band']:>5} {r['pen_lifts']:>5} | "
            f"{r['length_ratio_median']:>7.2f} | {r['compose_ms_median']:>10.1f} "
            f"{r['compose_ratio']:>6.2f}{flag}"
        )
    RESULTS.mkdir(exist_ok=True)
    out = RESULTS / "bench_connections.json"
    write_json(out, {"settings": {"words": list(WORDS), "target": TARGET}, "rows": rows})
    print(f"\nwrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
