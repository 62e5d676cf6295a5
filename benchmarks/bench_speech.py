"""Benchmark phi_S: recogniser accuracy and latency per backend on espeak-ng words.

Every word of ``WORDS`` (48 common English words: the paper's bell, cat and jump, short and long
ones) is synthesised with espeak-ng in each ``--voices`` entry (default: ``en-us`` at 160 words
per minute and the female variant ``en+f3`` at 130), and recognised with each configuration:

- ``whisper``: faster-whisper, offline tiny.en (int8, 2 threads), free transcription — the
  reference the others are compared with;
- ``whisper+lexicon``: the lexicon (= ``WORDS``) as hotwords, transcript snapped to the nearest
  lexicon word;
- ``whisper+rescore``: the lexicon word of highest exact probability under Whisper's decoder;
- ``pocketsphinx``: PocketSphinx 5, default US English language model;
- ``pocketsphinx+grammar``: PocketSphinx with a JSGF grammar of the lexicon;
- ``wav2vec2``: measured only when ``--wav2vec2-model`` (default: the cached
  ``facebook/wav2vec2-base-960h``) loads without a download; otherwise listed as not measured,
  with the reason.

Per utterance the configurations run one after another (interleaved, so machine load affects
them alike); each recogniser is loaded and warmed up on one utterance before timing. Latency is
the wall time of ``recognise(path, params)`` (read, resample, checks, recognition) with
``time.perf_counter``. A word counts as correct when the written word equals it exactly; the
letter error rate (LER) is the edit distance between written and spoken word over the spoken
word's length (an utterance with no usable transcript counts as LER 1). Ratios: accuracy and
median latency of each configuration over the reference's, in the same run.

Usage: ``python benchmarks/bench_speech.py [--voices en-us:160 en+f3:130] [--limit N]``
Prints a table and writes ``benchmarks/results/bench_speech.json``.
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from prg.errors import UsageError
from prg.files import write_json
from prg.pipeline.speech import (
    DEFAULT_WAV2VEC2,
    SpeechSettings,
    get_recogniser,
    letter_error_rate,
    recognise,
)

RESULTS = Path(__file__).parent / "results"
REFERENCE = "whisper"
WORDS = (
    "bell", "cat", "jump", "dog", "sun", "book", "tree", "fish", "milk", "red", "blue", "green",
    "hello", "apple", "house", "water", "garden", "yellow", "seven", "table", "window", "happy",
    "music", "paper", "pencil", "school", "family", "morning", "orange", "purple", "doctor",
    "flower", "kitchen", "bottle", "letter", "robot", "camera", "chocolate", "elephant",
    "umbrella", "computer", "birthday", "tomorrow", "beautiful", "important", "different",
    "yesterday", "telephone",
)  # fmt: skip


def configurations(lexicon: tuple[str, ...], wav2vec2: str | None) -> dict[str, SpeechSettings]:
    configs = {
        "whisper": SpeechSettings(),
        "whisper+lexicon": SpeechSettings(lexicon=lexicon),
        "whisper+rescore": SpeechSettings(lexicon=lexicon, rescore=True),
        "pocketsphinx": SpeechSettings(backend="pocketsphinx"),
        "pocketsphinx+grammar": SpeechSettings(backend="pocketsphinx", lexicon=lexicon),
    }
    if wav2vec2 is not None:
        configs["wav2vec2"] = SpeechSettings(backend="wav2vec2", model=wav2vec2)
        configs["wav2vec2+rescore"] = SpeechSettings(
            backend="wav2vec2", model=wav2vec2, lexicon=lexicon, rescore=True
        )
    return configs


def synthesise(words, voices, folder: Path) -> list[tuple[str, str, Path]]:
    """(word, voice label, WAV path) for every word in every voice."""
    espeak = shutil.which("espeak-ng")
    if espeak is None:
        raise SystemExit("espeak-ng is not installed (apt-get install espeak-ng)")
    items = []
    for voice in voices:
        name, speed = voice.split(":")
        for word in words:
            path = folder / f"{name.replace('+', '_')}-{speed}-{word}.wav"
            subprocess.run([espeak, "-w", str(path), "-v", name, "-s", speed, word], check=True)
            items.append((word, voice, path))
    return items


def run_once(path: Path, params: SpeechSettings) -> tuple[str, float]:
    """(written word or "" when no usable transcript, seconds)."""
    start = time.perf_counter()
    try:
        word = recognise(path, params).word
    except UsageError as err:
        if "no letters or digits" not in str(err):
            raise
        word = ""
    return word, time.perf_counter() - start


def summarise(records: list[dict]) -> dict:
    ms = [1000 * r["seconds"] for r in records]
    return {
        "n": len(records),
        "accuracy": float(np.mean([r["correct"] for r in records])),
        "ler": float(np.mean([r["ler"] for r in records])),
        "median_ms": statistics.median(ms),
        "p90_ms": float(np.percentile(ms, 90)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--voices", nargs="+", default=["en-us:160", "en+f3:130"])
    parser.add_argument("--limit", type=int, default=None, help="only the first N words")
    parser.add_argument("--wav2vec2-model", default=DEFAULT_WAV2VEC2)
    args = parser.parse_args()

    words = WORDS[: args.limit] if args.limit else WORDS
    lexicon = tuple(words)
    not_measured = {}
    wav2vec2 = args.wav2vec2_model
    try:
        get_recogniser("wav2vec2", wav2vec2)
    except UsageError as err:
        not_measured["wav2vec2"] = str(err)
        wav2vec2 = None
    configs = configurations(lexicon, wav2vec2)

    with tempfile.TemporaryDirectory() as tmp:
        items = synthesise(words, args.voices, Path(tmp))
        for params in configs.values():  # load and warm up every recogniser, untimed
            get_recogniser(params.backend, params.model)
            run_once(items[0][2], params)
        records: dict[str, list[dict]] = {name: [] for name in configs}
        for k, (word, voice, path) in enumerate(items, 1):
            for name, params in configs.items():
                heard, seconds = run_once(path, params)
                records[name].append(
                    {
                        "word": word,
                        "voice": voice,
                        "heard": heard,
                        "correct": heard == word,
                        "ler": letter_error_rate(heard, word) if heard else 1.0,
                        "seconds": seconds,
                    }
                )
            if k % 12 == 0 or k == len(items):
                print(f"{k}/{len(items)} utterances", flush=True)

    summary = {}
    for name, recs in records.items():
        summary[name] = {"all": summarise(recs)}
        for voice in args.voices:
            summary[name][voice] = summarise([r for r in recs if r["voice"] == voice])
    ref = summary[REFERENCE]["all"]
    for name in summary:
        s = summary[name]["all"]
        s["accuracy_ratio"] = s["accuracy"] / ref["accuracy"] if ref["accuracy"] else None
        s["latency_ratio"] = s["median_ms"] / ref["median_ms"]

    n = len(items)
    print(
        f"\nphi_S on {len(words)} espeak-ng words x {len(args.voices)} voices "
        f"({', '.join(args.voices)}) = {n} utterances; reference: {REFERENCE}; "
        f"ratios = configuration / reference"
    )
    voice_cols = " | ".join(f"acc {v}" for v in args.voices)
    print(
        f"| configuration | accuracy | {voice_cols} | LER | acc ratio | median ms | p90 ms "
        "| latency ratio |"
    )
    print("|---|---:|" + "---:|" * len(args.voices) + "---:|---:|---:|---:|---:|")
    for name, s in summary.items():
        a = s["all"]
        per_voice = " | ".join(f"{s[v]['accuracy']:.1%}" for v in args.voices)
        ratio = "n/a" if a["accuracy_ratio"] is None else f"{a['accuracy_ratio']:.2f}"
        print(
            f"| {name} | {a['accuracy']:.1%} | {per_voice} | {a['ler']:.3f} | {ratio} | "
            f"{a['median_ms']:.0f} | {a['p90_ms']:.0f} | {a['latency_ratio']:.2f} |"
        )
    for name, reason in not_measured.items():
        print(f"| {name} | not measured: {reason} |")

    report = {
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "processor": platform.processor() or platform.machine(),
            "load_avg_at_end": [round(x, 2) for x in os.getloadavg()],
        },
        "settings": {
            "voices": args.voices,
            "words": list(words),
            "reference": REFERENCE,
            "configurations": {
                name: {
                    "backend": p.backend,
                    "model": p.model,
                    "lexicon": p.lexicon is not None,
                    "rescore": p.rescore,
                }
                for name, p in configs.items()
            },
            "latency": "wall time of recognise(path, params), recogniser loaded and warmed up",
        },
        "summary": summary,
        "not_measured": not_measured,
        "utterances": records,
    }
    RESULTS.mkdir(exist_ok=True)
    out = RESULTS / "bench_speech.json"
    write_json(out, report)
    print(f"\nwrote {out}")


if __name__ == "__main__":
    main()
