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
``mlflow=true`` one MLflow run holding them. The table is :mod:`prg.evaluation.dictaphone`'s;
this module reads the config and saves the outputs.

``words`` is a list (a bare ``words=bell`` is refused). A word given twice is written once, and
no two words share a folder: a word named like the table's own folder (``inputs``) or like an
earlier word up to case is written into ``<word>-2`` (each row of ``metrics.json`` names its
``folder``; :func:`prg.evaluation.dictaphone.word_folders`).
"""

from __future__ import annotations

import json
import logging
from pathlib import Path
from typing import Any

import numpy as np
from omegaconf import DictConfig, OmegaConf

from prg.checks import check_values, literal_words
from prg.commands.cli import check_output
from prg.commands.settings import checkpoint_path, generate_settings, node, speech_settings
from prg.data.datamodule import check_model_shapes
from prg.data.store import load_split
from prg.errors import UsageError
from prg.evaluation.dictaphone import (
    CHANNELS,
    accuracy,
    dictaphone_table,
    table2_figure,
    table2_markdown,
)
from prg.files import staged_outputs, write_json, write_text
from prg.pipeline.compose import clean_text
from prg.resources import project_path
from prg.tracking import task_run
from prg.writer import Writer

log = logging.getLogger(__name__)


def dictaphone(cfg: DictConfig) -> dict[str, Any]:
    """Task: write every word from speech and from letter images; table, figure, metrics."""
    check_values(cfg)
    if isinstance(cfg.words, str) or not (
        OmegaConf.is_list(cfg.words) or isinstance(cfg.words, list | tuple)
    ):
        raise UsageError(
            f"words must be a list of single words, e.g. words=[bell,cat], got {cfg.words!r}"
        )
    words = [clean_text(w, key="words") for w in literal_words(cfg.words, "words")]
    if not words or any(" " in w for w in words):
        raise UsageError(f"words must be a list of single words, got {list(cfg.words)!r}")
    words = list(dict.fromkeys(words))  # a word given twice is one row (dictaphone_table)
    channels = list(cfg.channels)
    unknown = [c for c in channels if c not in CHANNELS]
    if unknown or not channels:
        raise UsageError(f"channels {channels!r}: choose from {', '.join(CHANNELS)}")
    speed = cfg.speed
    if isinstance(speed, bool) or not isinstance(speed, int | float) or not 0 < speed < np.inf:
        raise UsageError(f"speed must be a positive number of words per minute, got {speed!r}")
    if not isinstance(cfg.voice, str) or not cfg.voice.strip():
        raise UsageError(
            f"voice must name an espeak-ng voice (espeak-ng --voices), got {cfg.voice!r}"
        )
    settings, speech = generate_settings(cfg), speech_settings(cfg)
    out_dir = check_output(cfg.out_dir, "out_dir")
    ckpt = checkpoint_path(cfg)
    writer = Writer.from_checkpoint(ckpt, settings=settings, speech=speech, on_unknown="skip")
    test = _test_split(cfg) if "image" in channels else None
    with task_run(cfg, "dictaphone", {"prg.family": writer.family}, enabled=cfg.mlflow) as run:
        with staged_outputs(out_dir) as staging:
            rows, items = dictaphone_table(
                writer, words, channels, staging, test, cfg.voice, speed, record=cfg.record
            )
            table2_figure(words, channels, items, staging / "table2.png")
            markdown = table2_markdown(
                rows, writer.family, cfg.voice, speed, speech.backend, speech.lexicon
            )
            write_text(staging / "table2.md", markdown)
            metrics = {
                "family": writer.family,
                "ckpt": project_path(ckpt, cfg.paths.root_dir),
                "speech": node(cfg, "speech"),
                "voice": cfg.voice,
                "speed_wpm": speed,
                "rows": rows,
                "sound_accuracy": accuracy(rows, "sound"),
                "image_read_accuracy": accuracy(rows, "image"),
                "image_read_accuracy_folded": accuracy(rows, "image", folded=True),
            }
            write_json(staging / "metrics.json", metrics)
        log.info("Table II written to %s", out_dir)
        if run is not None:
            _log_run(run, cfg, metrics, out_dir)
    return metrics


def _test_split(cfg: DictConfig) -> dict[str, np.ndarray]:
    path = Path(cfg.paths.data_dir) / "prepared" / cfg.data_name / "test.npz"
    if not path.exists():
        raise UsageError(f"test split {path} does not exist: run prg-prepare first")
    test = load_split(path)
    check_model_shapes(test, path.parent)
    return test


def _log_run(run, cfg: DictConfig, metrics: dict, out_dir: Path) -> None:
    run.log_params(
        {
            "words": json.dumps(list(cfg.words)),
            "speech": json.dumps(metrics["speech"]),
            "voice": f"{cfg.voice} {cfg.speed} wpm",
        }
    )
    run.log_metrics(
        {
            key: metrics[key]
            for key in ("sound_accuracy", "image_read_accuracy", "image_read_accuracy_folded")
        },
        prefix="dictaphone/",
    )
    run.log_metrics(
        {f"{row['word']}_{row['channel']}_rmse_mm": row["dmp_rmse_mm"] for row in metrics["rows"]},
        prefix="dictaphone/",
    )
    run.log_artifacts(out_dir, "dictaphone")


if __name__ == "__main__":
    from prg.commands.entry import dictaphone

    dictaphone()
