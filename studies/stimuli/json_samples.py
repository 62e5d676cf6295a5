"""Reading the JSON sample files: capture-page sessions, strokes documents, word trajectories."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from prg.errors import UsageError
from studies.stimuli.sample import Sample, _identity_from_path, _need
from studies.stimuli.trajectories import trajectory_sample

CAPTURE_SCHEMA = "prg.handwriting_capture"
CAPTURE_VERSION = 1
WORD_SCHEMA = "prg.word_trajectory"


def _points(raw, where: str) -> np.ndarray:
    try:
        rows = [list(p)[:2] for p in raw]
        pts = np.asarray(rows, dtype=np.float64).reshape(-1, 2)
    except (TypeError, ValueError):
        raise UsageError(f"{where}: a stroke must be a list of [x, y, ...] numbers") from None
    if not np.all(np.isfinite(pts)):
        raise UsageError(f"{where}: a stroke holds NaN or infinite numbers")
    return pts


def _strokes(
    raw, where: str, y_down: bool, delayed=None
) -> tuple[tuple[np.ndarray, ...], tuple[int, ...]]:
    """The non-empty strokes of ``raw`` (y up) and the indices among them of the delayed
    strokes that ``delayed`` lists (indices into ``raw``; None: none)."""
    if not isinstance(raw, list):
        raise UsageError(f"{where}: strokes must be a list of strokes, each a list of [x, y]")
    if delayed is None:
        delayed = []
    if (
        not isinstance(delayed, list)
        or not all(isinstance(k, int) and not isinstance(k, bool) for k in delayed)
        or not all(1 <= k < len(raw) for k in delayed)
        or len(set(delayed)) != len(delayed)
    ):
        accepted = f"1 to {len(raw) - 1}" if len(raw) > 1 else "none: there is one stroke"
        raise UsageError(
            f"{where}: delayed must list strokes after the first by index ({accepted}), "
            f"each once, got {delayed!r}"
        )
    out, kept = [], []
    for i, stroke in enumerate(raw):
        if not isinstance(stroke, list):
            raise UsageError(f"{where}: each stroke must be a list of [x, y] points")
        pts = _points(stroke, where)
        if len(pts):
            if i in delayed and out:  # a delayed stroke after an empty first one is the word
                kept.append(len(out))
            out.append(pts * [1.0, -1.0] if y_down else pts)
    return tuple(out), tuple(kept)


def is_lifted(n_strokes: int, delayed: Sequence[int], flagged: bool = False) -> bool:
    """Whether a sample was written with a pen lift: flagged so, or a stroke after the first
    that is not a delayed stroke."""
    return bool(flagged) or n_strokes - 1 > len(delayed)


def read_capture(doc: dict, where: str) -> list[Sample]:
    """Samples of a capture-page document (schema ``prg.handwriting_capture``)."""
    if doc.get("version") != CAPTURE_VERSION:
        raise UsageError(
            f"{where}: capture version {doc.get('version')!r} is not supported "
            f"(accepted: {CAPTURE_VERSION})"
        )
    writer = doc.get("writer_id")
    if not isinstance(writer, str) or not writer.strip():
        raise UsageError(f"{where}: writer_id must be a non-empty string")
    y_down = bool(doc.get("canvas", {}).get("y_down", True))
    samples = doc.get("samples")
    if not isinstance(samples, list):
        raise UsageError(f"{where}: samples must be a list")
    out = []
    for i, entry in enumerate(samples):
        here = f"{where}: samples[{i}]"
        if not isinstance(entry, dict) or not isinstance(entry.get("word"), str):
            raise UsageError(f"{here} must be an object with word and strokes")
        strokes, delayed = _strokes(entry.get("strokes"), here, y_down, entry.get("delayed"))
        if not strokes:
            continue  # a skipped word
        lifted = is_lifted(len(strokes), delayed, entry.get("lifted", False))
        out.append(Sample(entry["word"], writer.strip(), strokes, where, lifted, delayed))
    return out


def read_json_sample(path: Path, root: Path) -> list[Sample]:
    """Samples in one JSON file: a capture, a strokes document or a word trajectory."""
    where = str(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as err:
        raise UsageError(f"{where}: cannot read ({err})") from None
    except json.JSONDecodeError as err:
        raise UsageError(f"{where}: not valid JSON ({err.msg} at line {err.lineno})") from None
    if isinstance(doc, dict) and doc.get("schema") == CAPTURE_SCHEMA:
        return read_capture(doc, where)
    word, writer = _identity_from_path(path, root)
    if isinstance(doc, dict) and doc.get("schema") == WORD_SCHEMA:
        from prg.pipeline.word import WordTrajectory

        traj = WordTrajectory.from_json(path)
        return [trajectory_sample(traj, _need(writer, where), where)]
    y_down, delayed = False, None
    if isinstance(doc, dict):
        word = doc.get("word", word)
        writer = doc.get("writer_id", writer)
        y_down = bool(doc.get("y_down", False))
        delayed = doc.get("delayed")
        doc = doc.get("strokes")
    strokes, delayed = _strokes(doc, where, y_down, delayed)
    if not strokes:
        raise UsageError(f"{where}: no strokes")
    lifted = is_lifted(len(strokes), delayed)
    return [Sample(str(word), _need(writer, where), strokes, where, lifted, delayed)]
