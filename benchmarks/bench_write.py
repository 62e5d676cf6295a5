"""Benchmark writing a word: label input -> letters -> layout -> connections -> one DMP rollout.

For words of 1-12 letters (``--reps`` random lowercase words per length, seeded), the whole
``prg.writer.Writer.generate`` path of a warm writer is timed in the default settings
(``GenerateSettings()``: letters in a writer's hand, ``generate.mode=hand``; decode every
letter, final processing map, the hand joins, ``generate.method=hand``, the human timing,
``generate.timing=human``, DMP fit and rollout), side by side in the same run with two
references:

- ``decode``: the model's generation map alone for the same letters (one batched
  ``model.generate`` under ``torch.no_grad``: the plain PyTorch floor) — ratio total / decode
  says what the rest of the pipeline costs;
- ``straight``: the same pipeline with the paper's straight-line joiner instead of the hand
  joins — ratio default / straight is the price of joining letters as a hand does.

It also reports the DMP's reproduction error (RMSE and max, mm, rollout against the timed
demonstration) with the default settings (``conf/write.yaml``: 70 basis functions per 100
samples at 100 samples/s). Target: median under 50 ms for 6 letters; RMSE under 0.1 mm.

With ``--speech``, speech input end to end in a warm process, per recogniser setting (wav2vec2
has no real model offline), on the paper's words, for the first family: a ``Writer`` built once
writes each espeak-ng file (``Writer.write(audio=...)``: read, recognise, letters, layout,
connections, DMP rollout) against ``recognise`` alone on the same file, alternated ``--reps``
times (medians); target ratio <= 1.2. An utterance the recogniser refuses (nothing heard) is timed up to the refusal.

Models: ``models/<family>/model.ckpt`` (``make demo``) when present, else the family built from
``conf/model`` with seeded random weights (speed does not depend on the weights; RMSE does).

Usage: ``python benchmarks/bench_write.py [--families muse avae_ts] [--reps 7] [--speech]``
Prints a table and writes ``benchmarks/results/bench_write.json``.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import platform
import random
import statistics
import string
import subprocess
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import torch
from omegaconf import OmegaConf

from prg.commands.cli import compose_config
from prg.errors import UsageError
from prg.files import write_json
from prg.models.checkpoint import load_model
from prg.pipeline.compose import GenerateSettings
from prg.pipeline.decode import label_inputs, usable_inputs
from prg.pipeline.timing import timed_body
from prg.writer import Perception, Writer

RESULTS = Path(__file__).parent / "results"
ROOT = Path(__file__).parent.parent
TARGET_MS = 50.0
TARGET_RMSE_MM = 0.1
TARGET_SPEECH_RATIO = 1.2  # warm Writer.write(audio=) over recognise() alone
PAPER_WORDS = ("bell", "cat", "jump")
# wav2vec2 is left out: no real model is available offline here (benchmarks/bench_speech.py)
SPEECH_SETTINGS = {
    "whisper": {"backend": "whisper"},
    "whisper+lexicon": {"backend": "whisper", "lexicon": PAPER_WORDS},
    "whisper+rescore": {"backend": "whisper", "lexicon": PAPER_WORDS, "rescore": True},
    "pocketsphinx+grammar": {"backend": "pocketsphinx", "lexicon": PAPER_WORDS},
}


def family_model(family: str):
    """The demo model of ``family`` and its checkpoint's hands, or seeded random weights and
    no hands; and where it came from."""
    ckpt = ROOT / "models" / family / "model.ckpt"
    if ckpt.exists():
        model, info = load_model(ckpt)
        return model, info.get("hands"), str(ckpt.relative_to(ROOT))
    from hydra.utils import instantiate

    torch.manual_seed(0)
    cfg = compose_config("train", [f"model={family}"]).model.module
    model = instantiate(OmegaConf.to_container(cfg, resolve=True))
    return model, None, "random weights (no demo model: the posterior decoding, no hands)"


def words_of(length: int, reps: int, rng: random.Random) -> list[str]:
    return ["".join(rng.choice(string.ascii_lowercase) for _ in range(length)) for _ in range(reps)]


def time_word(writer: Writer, straight: Writer, text: str) -> dict:
    """One word by two warm writers (the default joins and the straight joiner), and the
    model's generation map alone."""
    model, params = writer.model, writer.settings
    inputs = label_inputs(text)
    start = time.perf_counter()
    with torch.no_grad():
        model.generate(usable_inputs(model, inputs), "traj", n=1)
    decode = time.perf_counter() - start
    start = time.perf_counter()
    result = writer.generate(Perception(text, inputs))
    word, path = result.word, result.rollout
    total = time.perf_counter() - start
    start = time.perf_counter()
    straight.generate(Perception(text, inputs))
    total_straight = time.perf_counter() - start
    samples, _ = timed_body(word.body, params)
    error = np.linalg.norm(path - samples, axis=1) * 10  # mm
    return {
        "decode_ms": decode * 1000,
        "total_ms": total * 1000,
        "straight_ms": total_straight * 1000,
        "rmse_mm": float(np.sqrt(np.mean(error**2))),
        "max_mm": float(error.max()),
        "points": len(samples),
        "basis": word.dmp.n_basis,
        "width_cm": float(np.ptp(word.points[:, 0])),
    }


def speech_rows(model, hands, family: str, params: GenerateSettings, reps: int) -> list[dict]:
    """Speech end to end in a warm process, per recogniser setting: a ``Writer`` built once
    writes each spoken word (``Writer.write(audio=...)``: read, recognise, letters, layout,
    connections, DMP rollout), timed against ``recognise`` alone on the same file, alternated
    rep by rep. Each word is written once untimed first (loads the recogniser, decodes its
    letters)."""
    from prg.pipeline import speech

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        audio = {}
        for word in PAPER_WORDS:
            wav = Path(tmp) / f"{word}.wav"
            subprocess.run(["espeak-ng", "-w", str(wav), word], check=True)
            audio[word] = wav
        for backend, settings in SPEECH_SETTINGS.items():
            settings = speech.SpeechSettings(**settings)
            writer = Writer(model, params, speech=settings, on_unknown="skip", hands=hands)
            for word, wav in audio.items():
                with contextlib.suppress(UsageError):
                    writer.write(audio=wav)  # warm-up, untimed
                write_times, recognise_times, heard = [], [], None
                for _ in range(reps):
                    start = time.perf_counter()
                    try:
                        heard = speech.recognise(wav, settings).word
                    except UsageError:  # nothing usable heard: timed up to the refusal
                        heard = None
                    recognise_times.append(time.perf_counter() - start)
                    start = time.perf_counter()
                    with contextlib.suppress(UsageError):
                        writer.write(audio=wav)
                    write_times.append(time.perf_counter() - start)
                row = {
                    "family": family,
                    "backend": backend,
                    "word": word,
                    "heard": heard,
                    "recognise_ms": 1000 * statistics.median(recognise_times),
                    "total_ms": 1000 * statistics.median(write_times),
                }
                row["ratio"] = row["total_ms"] / row["recognise_ms"]
                rows.append(row)
                print(
                    f"speech {backend} {word!r} -> {heard!r}: {row['total_ms']:.0f} ms "
                    f"({row['ratio']:.2f}x recognise alone)",
                    flush=True,
                )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--families", nargs="+", default=["muse", "avae_ts"])
    parser.add_argument("--lengths", nargs="+", type=int, default=[1, 2, 4, 6, 8, 10, 12])
    parser.add_argument("--reps", type=int, default=7, help="words per length")
    parser.add_argument("--threads", type=int, default=1, help="torch threads")
    parser.add_argument("--speech", action="store_true", help="also time speech input")
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    rows, speech, sources = [], [], {}
    for family in args.families:
        model, hands, sources[family] = family_model(family)
        # warm writers, as a served model's: the default hand decoding where the checkpoint
        # has hands (its decoder bias estimated once, by the warm-up word)
        params = GenerateSettings() if hands is not None else GenerateSettings(mode="posterior")
        writer = Writer(model, params, hands=hands)
        straight = Writer(model, replace(params, method="straight"), hands=hands)
        time_word(writer, straight, "warm")
        rng = random.Random(0)
        for length in args.lengths:
            runs = [time_word(writer, straight, w) for w in words_of(length, args.reps, rng)]
            row = {"family": family, "letters": length}
            for key in runs[0]:
                row[key] = statistics.median(r[key] for r in runs)
            row["max_rmse_mm"] = max(r["rmse_mm"] for r in runs)
            row["max_mm"] = max(r["max_mm"] for r in runs)
            rows.append(row)
            print(
                f"{family} {length} letters: {row['total_ms']:.1f} ms "
                f"(decode {row['decode_ms']:.1f}), RMSE {row['rmse_mm']:.3f} mm",
                flush=True,
            )
        if args.speech and family == args.families[0]:
            speech += speech_rows(model, hands, family, params, args.reps)

    print(
        f"\nWrite latency, label input -> DMP rollout, median of {args.reps} random words per "
        f"length, {args.threads} torch thread(s); RMSE of the DMP rollout against its "
        f"demonstration (median / worst of the words)"
    )
    header = (
        f"{'family':>8}{'letters':>8} | {'default':>8}{'decode':>8}{'ratio':>7} | "
        f"{'straight':>9}{'ratio':>7} | {'RMSE mm':>8}{'worst':>7}{'max mm':>8} | {'basis':>6}"
    )
    print(header)
    print("-" * len(header))
    for r in rows:
        flag = ""
        if (r["letters"] == 6 and r["total_ms"] > TARGET_MS) or r["max_rmse_mm"] > TARGET_RMSE_MM:
            flag = "  < target"
        print(
            f"{r['family']:>8}{r['letters']:>8} | {r['total_ms']:>6.1f}ms{r['decode_ms']:>6.1f}ms"
            f"{r['total_ms'] / r['decode_ms']:>7.1f} | {r['straight_ms']:>7.1f}ms"
            f"{r['total_ms'] / r['straight_ms']:>7.2f} | {r['rmse_mm']:>8.3f}"
            f"{r['max_rmse_mm']:>7.3f}{r['max_mm']:>8.3f} | {r['basis']:>6.0f}{flag}"
        )
    if speech:
        print(
            "\nSpeech input end to end in a warm process: Writer.write(audio=...) against "
            f"recognise() alone (target ratio <= {TARGET_SPEECH_RATIO})"
        )
        header = (
            f"{'family':>8} {'backend':>21} {'word':>6} {'heard':>8} | {'recognise':>10}"
            f"{'write':>9}{'ratio':>7}"
        )
        print(header)
        print("-" * len(header))
        for r in speech:
            print(
                f"{r['family']:>8} {r['backend']:>21} {r['word']:>6} {r['heard']!s:>8} | "
                f"{r['recognise_ms']:>8.0f}ms{r['total_ms']:>7.0f}ms{r['ratio']:>7.2f}"
            )
    report = {
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "torch": torch.__version__,
            "processor": platform.processor() or platform.machine(),
            "load_avg_at_end": [round(x, 2) for x in os.getloadavg()],
        },
        "settings": {
            "reps": args.reps,
            "threads": args.threads,
            "generate": {k: str(v) for k, v in GenerateSettings().__dict__.items()},
            "models": sources,
            "target_ms_6_letters": TARGET_MS,
            "target_rmse_mm": TARGET_RMSE_MM,
            "target_speech_ratio": TARGET_SPEECH_RATIO,
        },
        "rows": rows,
        "speech": speech,
    }
    RESULTS.mkdir(exist_ok=True)
    out = RESULTS / "bench_write.json"
    write_json(out, report)
    print(f"\nwrote {out}")


if __name__ == "__main__":
    main()
