"""``prg-dictaphone``: the paper's Robotic Dictaphone demonstration (its Table II), reproduced.

For each word (the paper's ``bell``, ``cat``, ``jump`` by default) the trained model writes the
word twice:

- **from sound** (x_S): the word is spoken by espeak-ng (``voice``, ``speed`` wpm) into a WAV
  file, recognised by phi_S (``speech`` settings, the same as ``prg-write``'s), and the
  transcript's letters are the model's only input;
- **from images** (x_I): one image per letter, taken from the test split (the first original,
  non-augmented test sample of each letter's class), saved as dark-on-light PNGs; the images are
  the model's only input, and the word's known spelling sizes and places the letters (what the
  model itself reads from the images is reported beside it).

Outputs in ``out_dir`` (default ``reports/dictaphone``), written atomically:
``inputs/<word>.wav`` and ``inputs/<word>/<i>_<c>.png`` (the inputs, reusable with
``prg-write audio=...`` / ``images=...``), ``<word>/<sound|image>/`` (``word.json``, ``.png``,
``.svg``, ``.rrd``, ``dmp_rollout.csv``, as ``prg-write``), ``table2.png`` (inputs above —
spectrogram or letter images — and the written words below, as the paper's table),
``table2.md`` and ``metrics.json`` (what was heard and read, latency, DMP error); with
``mlflow=true`` one MLflow run holding them.
"""

from __future__ import annotations

import json
import logging
import shutil
import subprocess
import time
from pathlib import Path
from typing import Any

import numpy as np
from omegaconf import DictConfig, OmegaConf
from scipy.signal import spectrogram

from prg.checks import check_values, literal_words
from prg.commands.cli import check_output, hydra_command
from prg.commands.write import image_inputs, params_from_config, save_outputs, speech_input
from prg.commands.write import speech_params_from_config as speech_settings
from prg.data.alphabet import char_to_label
from prg.data.datamodule import check_model_shapes
from prg.data.store import load_split
from prg.errors import UsageError
from prg.files import atomic_path, staged_outputs, write_json
from prg.models.checkpoint import load_model
from prg.pipeline.decode import check_inputs, decode_letters, infer_text, label_inputs
from prg.pipeline.compose import clean_text, compose_word
from prg.pipeline.timing import rest_to_rest_samples
from prg.pipeline.speech import SAMPLE_RATE
from prg.pipeline.word import WordTrajectory
from prg.plotting import pyplot

log = logging.getLogger(__name__)

CHANNELS = ("sound", "image")


def espeak(text: str, path: Path, voice: str = "en-us", speed: int = 150) -> Path:
    """Speak ``text`` with espeak-ng into the WAV file ``path``."""
    if shutil.which("espeak-ng") is None:
        raise UsageError("espeak-ng is not installed: apt-get install espeak-ng (make setup)")
    result = subprocess.run(
        ["espeak-ng", "-v", voice, "-s", str(int(speed)), "-w", str(path), text],
        capture_output=True,
        text=True,
    )
    if result.returncode != 0 or not path.exists():
        message = " ".join(result.stderr.split()) or f"exit code {result.returncode}"
        raise UsageError(f"espeak-ng could not speak {text!r} with voice {voice!r}: {message}")
    return path


def letter_images(test: dict[str, np.ndarray], word: str) -> list[np.ndarray]:
    """One dark-on-light image per letter of ``word``: the first original (non-augmented) test
    sample of its class, else the first augmented one."""
    images = []
    for char in word:
        label = char_to_label(char)
        matches = np.flatnonzero(test["label"] == label)
        if matches.size == 0:
            raise UsageError(f"the test split has no image of {char!r}: cannot show {word!r}")
        originals = matches[~test["augmented"][matches]]
        index = originals[0] if originals.size else matches[0]
        images.append(255 - test["image"][index])
    return images


def dmp_rmse_mm(word: WordTrajectory, rollout: np.ndarray, params) -> float:
    """RMSE (mm) of the DMP rollout against the timed demonstration it was fitted to."""
    samples, _ = rest_to_rest_samples(
        word.points, params.speed_cm_s, params.ramp_s, params.samples_per_s
    )
    return float(np.sqrt(np.mean(np.sum((rollout - samples) ** 2, axis=1))) * 10)


def dictaphone(cfg: DictConfig) -> dict[str, Any]:
    """Task: write every word from speech and from letter images; table, figure, metrics."""
    check_values(cfg)
    words = [clean_text(w, key="words") for w in literal_words(cfg.words, "words")]
    if not words or any(" " in w for w in words):
        raise UsageError(f"words must be a list of single words, got {list(cfg.words)!r}")
    unknown = [c for c in cfg.channels if c not in CHANNELS]
    if unknown or not cfg.channels:
        raise UsageError(f"channels {list(cfg.channels)!r}: choose from {', '.join(CHANNELS)}")
    speed = cfg.speed
    if isinstance(speed, bool) or not isinstance(speed, int | float) or not 0 < speed < np.inf:
        raise UsageError(f"speed must be a positive number of words per minute, got {speed!r}")
    if not isinstance(cfg.voice, str) or not cfg.voice.strip():
        raise UsageError(
            f"voice must name an espeak-ng voice (espeak-ng --voices), got {cfg.voice!r}"
        )
    params = params_from_config(cfg)
    settings = speech_settings(cfg)
    out_dir = check_output(cfg.out_dir, "out_dir")
    ckpt = Path(cfg.ckpt) if cfg.ckpt else Path(cfg.models_dir) / cfg.family / "model.ckpt"
    model, _ = load_model(ckpt)
    test_path = Path(cfg.paths.data_dir) / "prepared" / cfg.data_name / "test.npz"
    if "image" in cfg.channels and not test_path.exists():
        raise UsageError(f"test split {test_path} does not exist: run prg-prepare first")
    test = load_split(test_path) if "image" in cfg.channels else None
    if test is not None:
        check_model_shapes(test, test_path.parent)

    rows, figure_inputs = [], {}
    with staged_outputs(out_dir) as staging:
        inputs_dir = staging / "inputs"
        inputs_dir.mkdir()
        for word in words:
            for channel in cfg.channels:
                start = time.perf_counter()
                record: dict[str, Any] = {}
                if channel == "sound":
                    wav = espeak(word, inputs_dir / f"{word}.wav", cfg.voice, cfg.speed)
                    heard = speech_input(wav, settings)
                    transcript = heard["transcript"]
                    text = clean_text(transcript.word, "skip")
                    inputs = label_inputs(text)
                    perceived = text
                    record = {
                        "audio": heard["samples"],
                        "sample_rate": SAMPLE_RATE,
                        "transcript": transcript.text,
                    }
                    figure_inputs[word, channel] = heard["samples"]
                else:
                    folder = inputs_dir / word
                    folder.mkdir()
                    images_of_word = letter_images(test, word)
                    for i, image in enumerate(images_of_word):
                        _save_png(image, folder / f"{i}_{word[i]}.png")
                    inputs = {"image": image_inputs(folder)}
                    text = word
                    perceived = _read(model, inputs)
                    figure_inputs[word, channel] = images_of_word
                check_inputs(text, inputs)
                letters = decode_letters(
                    model, inputs, params.temperature, params.seed, params.impute_steps
                )
                written, rollout = compose_word(letters, text, params)
                seconds = time.perf_counter() - start
                images = inputs.get("image")
                save_outputs(
                    written,
                    rollout,
                    staging / word / channel,
                    {
                        "letters": letters,
                        "images": None if images is None else images.numpy(),
                        **record,
                    }
                    if cfg.record
                    else None,
                )
                rows.append(
                    {
                        "word": word,
                        "channel": channel,
                        "perceived": perceived,
                        "correct": perceived == word,
                        "written": written.text,
                        "seconds": round(seconds, 3),
                        "dmp_rmse_mm": round(dmp_rmse_mm(written, rollout, params), 4),
                        "path_length_cm": round(written.path_length, 2),
                        "duration_s": round(written.duration_s, 2),
                    }
                )
                log.info(
                    "%s from %s: perceived %r, wrote %r in %.2f s",
                    word,
                    channel,
                    perceived,
                    written.text,
                    seconds,
                )
                figure_inputs[word, channel, "word"] = written
        _figure(words, list(cfg.channels), figure_inputs, staging / "table2.png")
        (staging / "table2.md").write_text(_markdown(rows, cfg, model.family))
        metrics = {
            "family": model.family,
            "ckpt": str(ckpt),
            "speech": OmegaConf.to_container(cfg.speech, resolve=True),
            "voice": cfg.voice,
            "speed_wpm": cfg.speed,
            "rows": rows,
            "sound_accuracy": _accuracy(rows, "sound"),
            "image_read_accuracy": _accuracy(rows, "image"),
        }
        write_json(staging / "metrics.json", metrics)
    log.info("Table II written to %s", out_dir)
    if cfg.mlflow:
        _log_run(cfg, metrics, out_dir)
    return metrics


def _read(model, inputs) -> str:
    try:
        return infer_text(model, inputs)
    except UsageError:  # the family does not generate labels
        return ""


def _accuracy(rows: list[dict], channel: str) -> float | None:
    chosen = [r["correct"] for r in rows if r["channel"] == channel]
    return round(float(np.mean(chosen)), 3) if chosen else None


def _save_png(image: np.ndarray, path: Path) -> None:
    from PIL import Image

    Image.fromarray(np.asarray(image, dtype=np.uint8)).save(path)


def _markdown(rows: list[dict], cfg: DictConfig, family: str) -> str:
    lines = [
        f"# Table II — words written by {family} from sound and from letter images",
        "",
        f"Sound: espeak-ng voice `{cfg.voice}` at {cfg.speed} wpm, recognised by "
        f"`{cfg.speech.backend}` (lexicon: {list(cfg.speech.lexicon or []) or 'none'}). "
        "Images: the first original test-split image of each letter; the model reads them "
        "(column *perceived*) and the word's spelling places the letters.",
        "",
        "| word | input | perceived | written | DMP RMSE (mm) | writing (s) | latency (s) |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['word']} | {r['channel']} | {r['perceived'] or '-'} | {r['written']} | "
            f"{r['dmp_rmse_mm']:.3f} | {r['duration_s']:.1f} | {r['seconds']:.2f} |"
        )
    lines += ["", "Figure: `table2.png`; per-word outputs and Rerun recordings in `<word>/`.", ""]
    return "\n".join(lines)


def _figure(words: list[str], channels: list[str], items: dict, path: Path) -> None:
    """Inputs (spectrogram or letter images) above, written words below, one column per case."""
    plt = pyplot()
    columns = [(w, c) for w in words for c in channels]
    fig, axes = plt.subplots(
        2, len(columns), figsize=(2.6 * len(columns), 3.4), squeeze=False, height_ratios=[1, 1]
    )
    for col, (word, channel) in enumerate(columns):
        top, bottom = axes[0, col], axes[1, col]
        source = items[word, channel]
        if channel == "sound":
            freqs, _, power = spectrogram(source, fs=SAMPLE_RATE, nperseg=256, noverlap=192)
            shown = freqs <= 6000
            decibels = 10 * np.log10(power[shown] + 1e-12)  # digital silence has zero power
            top.imshow(
                decibels,
                origin="lower",
                aspect="auto",
                cmap="magma",
                vmin=decibels.max() - 80,
                extent=(0, len(source) / SAMPLE_RATE, 0, freqs[shown][-1]),
            )
        else:
            top.imshow(np.concatenate(source, axis=1), cmap="gray", vmin=0, vmax=255)
        top.set_title(f"{word}: {channel}", fontsize=10)
        top.set_xticks([])
        top.set_yticks([])
        written: WordTrajectory = items[word, channel, "word"]
        for kind, segment in written.polylines(highlight=False):
            colour = "black" if kind == "letter" else "tab:orange"
            bottom.plot(segment[:, 0], segment[:, 1], color=colour, linewidth=1.2)
        bottom.set_aspect("equal")
        bottom.axis("off")
    axes[0, 0].set_ylabel("input")
    axes[1, 0].set_ylabel("output")
    fig.suptitle("Words from sound (x_S) and from letter images (x_I)", fontsize=11)
    fig.tight_layout()
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=120)
    finally:
        plt.close(fig)


def _log_run(cfg: DictConfig, metrics: dict, out_dir: Path) -> None:
    from prg.tracking import task_client

    client, experiment = task_client(cfg)
    run = client.create_run(
        experiment,
        run_name=cfg.run_name,
        tags={"prg.task": "dictaphone", "prg.family": metrics["family"]},
    )
    run_id = run.info.run_id
    client.log_param(run_id, "words", json.dumps(list(cfg.words)))
    client.log_param(run_id, "speech", json.dumps(metrics["speech"]))
    client.log_param(run_id, "voice", f"{cfg.voice} {cfg.speed} wpm")
    for key in ("sound_accuracy", "image_read_accuracy"):
        if metrics[key] is not None:
            client.log_metric(run_id, f"dictaphone/{key}", metrics[key])
    for row in metrics["rows"]:
        client.log_metric(
            run_id, f"dictaphone/{row['word']}_{row['channel']}_rmse_mm", row["dmp_rmse_mm"]
        )
    client.log_artifacts(run_id, str(out_dir), "dictaphone")
    client.set_terminated(run_id)


main = hydra_command(dictaphone, "dictaphone", "prg-dictaphone")

if __name__ == "__main__":
    main()
