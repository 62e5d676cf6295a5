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
``dmp_rollout.csv`` into ``out_dir`` (atomically, through a staging folder) and, with
``mlflow=true``, an MLflow run holding them.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
import os
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch
from omegaconf import DictConfig, OmegaConf

from prg.checks import check_text_length, check_values, literal_text, literal_words
from prg.commands.cli import check_output, hydra_command
from prg.errors import UsageError
from prg.files import staged_outputs
from prg.models.checkpoint import load_model
from prg.pipeline.connect import ConnectionSettings
from prg.pipeline.decode import check_inputs, decode_letters, infer_text, label_inputs
from prg.pipeline.compose import GenerateSettings, clean_text, compose_word
from prg.pipeline.layout import LayoutSettings
from prg.pipeline.perceive import (
    load_image,
    perceive_letter_images,
    perceive_trajectories,
    segment_word_image,
)
from prg.pipeline.speech import SAMPLE_RATE, SpeechSettings
from prg.pipeline.word import WordTrajectory
from prg.recording import record_write

log = logging.getLogger(__name__)


def params_from_config(cfg: DictConfig) -> GenerateSettings:
    """The generation, layout and connection settings as :class:`GenerateSettings`."""
    connection = OmegaConf.to_container(cfg.connection, resolve=True)
    connection["alpha_max"] = math.radians(connection.pop("alpha_max_deg"))
    try:
        return GenerateSettings(
            **OmegaConf.to_container(cfg.generate, resolve=True),
            layout=LayoutSettings(**OmegaConf.to_container(cfg.layout, resolve=True)),
            connection=ConnectionSettings(**connection),
        )
    except (TypeError, ValueError) as err:
        raise UsageError(f"write settings: {err}") from None


def image_inputs(path: str | os.PathLike) -> torch.Tensor:
    """The I channel from a word image (segmented into letters) or a folder of letter images."""
    path = Path(path)
    if path.is_dir():
        files = sorted(p for p in path.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
        if not files:
            raise UsageError(f"images folder {path} holds no {'/'.join(IMAGE_SUFFIXES)} files")
        letters = [load_image(f) for f in files]
    else:
        letters = segment_word_image(load_image(path), name=f"images={path}")
    return torch.from_numpy(perceive_letter_images(letters))


IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")


def trajectory_inputs(path: str | os.PathLike) -> torch.Tensor:
    """The T channel from a JSON file: ``{"strokes": [[[x, y], ...], ...], "y_down": false}``
    (one pen-down stroke per letter, any scale) or a bare list of strokes."""
    path = Path(path)
    try:
        doc = json.loads(path.read_text())
    except FileNotFoundError:
        raise UsageError(f"trajectories file {path} does not exist") from None
    except (OSError, ValueError) as err:
        raise UsageError(f"trajectories file {path} is not readable JSON ({err})") from None
    strokes, y_down = (doc, False) if isinstance(doc, list) else (None, False)
    if isinstance(doc, dict):
        strokes, y_down = doc.get("strokes"), bool(doc.get("y_down", False))
    if not isinstance(strokes, list) or not strokes:
        raise UsageError(
            f"trajectories file {path}: expected a non-empty list of strokes, each a list of "
            '[x, y] points (or {"strokes": [...], "y_down": bool})'
        )
    try:
        arrays = [np.asarray(stroke, dtype=np.float64) for stroke in strokes]
    except (TypeError, ValueError):
        raise UsageError(f"trajectories file {path}: strokes must hold [x, y] numbers") from None
    return torch.from_numpy(perceive_trajectories(arrays, y_down=y_down))


MAX_LEXICON_BYTES = 1_000_000  # a word list, not a dictionary dump: about 100,000 words


def read_lexicon(path: Path) -> list[str]:
    """The words of a lexicon file: UTF-8 text, one word (or short phrase) per line."""
    hint = "give a text file with one word per line, or a list: speech.lexicon=[bell,cat]"
    try:
        if path.stat().st_size > MAX_LEXICON_BYTES:
            raise UsageError(
                f"speech.lexicon {path}: {path.stat().st_size:,} bytes; accepted are word lists "
                f"up to {MAX_LEXICON_BYTES:,} bytes"
            )
        text = path.read_bytes().decode("utf-8")
    except OSError as err:
        raise UsageError(
            f"speech.lexicon {path}: not a readable word list ({err.strerror}); {hint}"
        ) from None
    except UnicodeDecodeError as err:
        raise UsageError(
            f"speech.lexicon {path}: not UTF-8 text (byte {err.start}); {hint}"
        ) from None
    if any(ord(c) < 32 and c not in "\t\r\n" for c in text):
        raise UsageError(f"speech.lexicon {path}: holds control characters, not text; {hint}")
    return [w for w in text.splitlines() if w.strip()]


def speech_params_from_config(cfg: DictConfig) -> SpeechSettings:
    """The ``speech`` settings as :class:`SpeechSettings`; ``lexicon`` may name a text file of
    words (one per line)."""
    settings = OmegaConf.to_container(cfg.speech, resolve=True)
    lexicon = settings.get("lexicon")
    if isinstance(lexicon, str):
        settings["lexicon"] = read_lexicon(Path(lexicon))
    elif lexicon is not None:
        settings["lexicon"] = literal_words(lexicon, "speech.lexicon")
    try:
        return SpeechSettings(**settings)
    except TypeError as err:
        raise UsageError(f"speech settings: {err}") from None


def speech_input(audio: str | os.PathLike, settings: SpeechSettings) -> dict[str, Any]:
    """phi_S on a sound file: its 16 kHz samples (for the recording) and the transcript."""
    from prg.pipeline.speech import load_audio, perceive_speech

    samples = load_audio(audio, max_seconds=settings.max_seconds)
    _, transcript = perceive_speech(audio, settings)
    log.info("heard %r (%s) in %.2f s", transcript.word, transcript.backend, transcript.seconds)
    return {"samples": samples, "transcript": transcript}


def write(cfg: DictConfig) -> tuple[WordTrajectory, Path]:
    """Task: generate the word and save it, its renderings and its DMP rollout."""
    check_values(cfg)
    text = literal_text(cfg.text, "text")
    text = None if text is None else text.strip()
    if cfg.text is not None and not text:
        raise UsageError("text is empty: give the word to write, e.g. text=hello")
    if text is not None and cfg.audio is not None:
        raise UsageError(
            "text and audio both give the S channel (the word's letters): give one of them"
        )
    if text is not None:
        text = clean_text(text, cfg.on_unknown)
    if all(cfg[channel] is None for channel in ("text", "audio", "images", "trajectories")):
        raise UsageError(
            "nothing to write: give text=WORD, audio=SOUND, images=PATH and/or trajectories=JSON"
        )
    params = params_from_config(cfg)
    out_dir = check_output(cfg.out_dir, "out_dir")
    speech = None
    if cfg.audio is not None:  # before the model: a bad recording fails fast
        speech = speech_input(cfg.audio, speech_params_from_config(cfg))
        text = clean_text(speech["transcript"].word, cfg.on_unknown)
    if params.method not in ("alg1", "straight"):
        raise UsageError(f"generate.method {params.method!r}: choose alg1 or straight")
    ckpt = Path(cfg.ckpt) if cfg.ckpt else Path(cfg.models_dir) / cfg.family / "model.ckpt"
    model, _ = load_model(ckpt)
    inputs = label_inputs(text) if text is not None else {}
    if cfg.images is not None:
        inputs["image"] = image_inputs(cfg.images)
    if cfg.trajectories is not None:
        inputs["traj"] = trajectory_inputs(cfg.trajectories)
    start = time.perf_counter()
    if text is None:
        text = infer_text(model, inputs)
        log.info("read %r from the images", text)
        check_text_length(text, "the word read from images=/trajectories=")
    check_inputs(text, inputs)
    letters = decode_letters(model, inputs, params.temperature, params.seed, params.impute_steps)
    word, path = compose_word(letters, text, params)
    seconds = time.perf_counter() - start
    recording = None
    if cfg.record:
        images = inputs.get("image")
        recording = {"letters": letters, "images": None if images is None else images.numpy()}
        if speech is not None:
            recording.update(
                audio=speech["samples"],
                sample_rate=SAMPLE_RATE,
                transcript=speech["transcript"].text,
            )
    save_outputs(word, path, out_dir, recording)
    log.info(
        "wrote %r with %s in %.0f ms: %d points, %.1f cm, %.1f s, DMP %d bases -> %s",
        text,
        model.family,
        seconds * 1000,
        len(word.points),
        word.path_length,
        word.duration_s,
        word.dmp["n_basis"],
        out_dir,
    )
    if cfg.mlflow:
        _log_run(cfg, word, out_dir, model.family, str(ckpt), seconds, speech)
    return word, out_dir


def save_outputs(
    word: WordTrajectory, path: np.ndarray, out_dir: Path, recording: dict | None = None
) -> None:
    """``word.json``, ``.png``, ``.svg``, ``dmp_rollout.csv`` and, given ``recording`` (keyword
    arguments of :func:`prg.recording.record_write`), ``word.rrd`` into ``out_dir``, atomically."""
    with staged_outputs(out_dir) as staging:
        if recording is not None:
            record_write(staging / "word.rrd", word, path, **recording)
        word.to_json(staging / "word.json")
        word.to_png(staging / "word.png")
        word.to_svg(staging / "word.svg")
        t = np.linspace(0.0, word.duration_s, len(path))
        np.savetxt(
            staging / "dmp_rollout.csv",
            np.column_stack([t, path]),
            delimiter=",",
            header="t_s,x_cm,y_cm",
            comments="",
            fmt="%.6f",
        )


def _log_run(cfg, word, out_dir: Path, family: str, ckpt: str, seconds: float, speech) -> None:
    from prg.tracking import task_client

    client, experiment = task_client(cfg)
    run = client.create_run(
        experiment,
        run_name=cfg.run_name,
        tags={"prg.task": "write", "prg.family": family, "prg.text": word.text},
    )
    run_id = run.info.run_id
    params: dict[str, Any] = {"text": word.text, "family": family, "ckpt": ckpt}
    params.update(
        {f"generate.{k}": v for k, v in dataclasses.asdict(params_from_config(cfg)).items()}
    )
    if speech is not None:
        transcript = speech["transcript"]
        params.update({f"speech.{k}": v for k, v in dataclasses.asdict(transcript).items()})
        params.update({"audio": str(cfg.audio)})
        client.log_metric(run_id, "write/recognise_ms", transcript.seconds * 1000)
    for key, value in params.items():
        client.log_param(run_id, key, str(value)[:500])
    for key, value in {
        "write/latency_ms": seconds * 1000,
        "write/points": len(word.points),
        "write/path_length_cm": word.path_length,
        "write/duration_s": word.duration_s,
        "write/dmp_basis": word.dmp["n_basis"],
    }.items():
        client.log_metric(run_id, key, float(value))
    client.log_artifacts(run_id, str(out_dir), "word")
    client.set_terminated(run_id)


main = hydra_command(write, "write", "prg-write")

if __name__ == "__main__":
    main()
