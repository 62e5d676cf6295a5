"""``prg-write``: write a word with a trained model — letters, connection strokes, one DMP.

Examples
--------
``prg-write text=hello``                          MUSE from ``models/muse/model.ckpt``
``prg-write text="the cat" family=avae_ts generate.method=straight``
``prg-write text=joy ckpt=checkpoints/prg/muse-seed0/best.ckpt generate.temperature=0.5``
``prg-write images=word.png``                     one image of a word (letters apart), MUSE
``prg-write images=letters/ text=cat``            per-letter images (sorted by name) + the text

Channels: ``text`` is the S channel (the labels, as a speech recogniser yields them) and the
layout; ``images`` (a word image, segmented into letters, or a folder of letter images) is the I
channel; ``trajectories`` (a JSON file of per-letter pen strokes) is the T channel. Without
``text`` the letters are read from the other channels by the model (S given I and/or T).

Writes ``word.json`` (points, segments, text, timing, DMP), ``word.png``, ``word.svg`` and
``dmp_rollout.csv``, ``motion.csv`` into ``out_dir`` (atomically, through a staging folder) and, with
``mlflow=true``, an MLflow run holding them, logged by a background process once the word is
written (``mlflow_background=false``: before the command returns; :func:`prg.tracking.task_run`). By default every word gets a new folder,
``outputs/write/<family>/<text>-<YYYYmmdd-HHMMSS>`` (``-2`` ... appended if it exists);
``out_dir=FOLDER`` names the folder (:func:`prg.files.word_folder`). The work is
:class:`prg.writer.Writer`'s; this module reads the config and saves the outputs.
"""

from __future__ import annotations

import dataclasses
import logging
from contextlib import nullcontext
from pathlib import Path
from typing import TYPE_CHECKING, Any

from omegaconf import DictConfig

from prg.checks import check_values, literal_text
from prg.commands.cli import check_output
from prg.commands.settings import checkpoint_path, writer_from_config
from prg.tracking import task_run

if TYPE_CHECKING:  # torch: imported by the task, once the command line is checked
    from prg.recorder import RecorderProcess
    from prg.writer import Writer, WriteResult

log = logging.getLogger(__name__)


def write(cfg: DictConfig) -> tuple[WriteResult, Path]:
    """Task: write the word given through the config's channels and save it, its renderings and
    its DMP rollout (and an MLflow run)."""
    from prg.files import folder_fields
    from prg.recorder import RecorderProcess

    check_values(cfg)
    text = literal_text(cfg.text, "text")
    folder_fields(cfg.out_dir)
    check_output(cfg.out_dir, "out_dir")
    # Rerun's imports, on the second core while this process loads torch and the model
    with RecorderProcess() if cfg.record else nullcontext() as recorder:
        return _write(cfg, text, recorder)


def _write(
    cfg: DictConfig, text: str | None, recorder: RecorderProcess | None
) -> tuple[WriteResult, Path]:
    from prg.files import word_folder

    writer = writer_from_config(cfg)
    with task_run(
        cfg,
        "write",
        {"prg.family": writer.family},
        enabled=cfg.mlflow,
        background=cfg.mlflow_background,
    ) as run:
        result = writer.write(text, cfg.audio, cfg.images, cfg.trajectories)
        with word_folder(cfg.out_dir, result.word.text) as out_dir:
            result.save(out_dir, record=cfg.record, recorder=recorder)
        word = result.word
        log.info(
            "wrote %r with %s in %.0f ms: %d points, %.1f cm, %.1f s, DMP %d bases, "
            "%d dots and bars -> %s",
            word.text,
            writer.family,
            result.timings["total"] * 1000,
            len(word.points),
            word.path_length,
            word.duration_s,
            word.dmp.n_basis,
            word.segment_kinds.count("mark"),
            out_dir,
        )
        if run is not None:
            _log_run(run, cfg, writer, result, out_dir)
    return result, out_dir


def _log_run(run, cfg: DictConfig, writer: Writer, result: WriteResult, out_dir: Path) -> None:
    word = result.word
    run.set_tag("prg.text", word.text)
    params: dict[str, Any] = {
        "text": word.text,
        "family": result.family,
        "ckpt": str(checkpoint_path(cfg)),
        "generate": dataclasses.asdict(writer.settings),
    }
    if cfg.get("style") is not None:
        params["style"] = str(cfg.style)
    transcript = result.perception.transcript
    if transcript is not None:
        params.update(speech=dataclasses.asdict(transcript), audio=str(cfg.audio))
        run.log_metrics({"write/recognise_ms": transcript.seconds * 1000})
    run.log_params(params)
    run.log_metrics(
        {
            "write/latency_ms": result.timings["total"] * 1000,
            "write/points": len(word.points),
            "write/path_length_cm": word.path_length,
            "write/duration_s": word.duration_s,
            "write/dmp_basis": word.dmp.n_basis,
        }
    )
    run.log_artifacts(out_dir, "word")


if __name__ == "__main__":
    from prg.commands.entry import write

    write()
