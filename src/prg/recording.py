"""Rerun recordings (``.rrd``) of a written word, and generic helpers to write and read them.

Every recording goes through an explicit :class:`rerun.RecordingStream` (never Rerun's global
recording) opened by :func:`recording_stream`, which writes to a temporary name in the
destination folder and renames it into place only when the ``with`` block ends cleanly: a reader
never sees half a file, and an error leaves nothing behind. ``rerun word.rrd`` opens the result.

:func:`record_write` logs what ``prg-write`` did (entity paths, all relative to the root):

==============================  ==================  ===============================================
entity                          archetype           when
==============================  ==================  ===============================================
``inputs/audio``                AssetAudio (WAV)    on ``audio_time`` 0 and ``time`` -duration
``inputs/waveform``             Scalars (min, max)  over ``audio_time`` and ``time`` (see below)
``inputs/transcript``           TextDocument        static
``inputs/images/<i>_<c>``       Image               static, one per letter image
``decoded/<i>_<c>``             LineStrips2D        static, raw normalised decoded letter
``word/letters/<i>_<c>``        LineStrips2D        static, the laid-out letter (ink colour)
``word/connections/<j>``        LineStrips2D        static, one colour per connection
``word/pen_up/<k>``             LineStrips2D        static, pen-up travel between words
``word/target``                 LineStrips2D        static, the demonstration path of the DMP
``word/rollout/pen``            Points2D            one row per rollout sample on ``time``
``word/rollout/path``           LineStrips2D        one segment per rollout step on ``time``
``summary``                     TextDocument        static (text, sizes, timing, DMP)
==============================  ==================  ===============================================

``<i>`` is the letter's index (zero-padded to the width of the largest index), ``<c>`` its
character, ``<j>``/``<k>`` the connection's / pen-up travel's index.

Coordinates
    Word coordinates are centimetres with y up (:class:`~prg.pipeline.word.WordTrajectory`), but
    Rerun's 2D views draw y down and ignore view coordinates in 2D. Every 2D position is therefore
    logged as ``(x, -y)``: the word reads upright in the viewer, and a reader of the file recovers
    centimetres, y up, by negating the second coordinate (:data:`Y_SIGN`). The raw decoded
    letters (normalised units, y up) are flipped the same way and set side by side with a
    :class:`rerun.Transform3D` translation of :data:`DECODED_SPACING` units per letter.

Timelines
    ``time`` (seconds, a duration timeline) is the writing: the DMP rollout of ``n`` samples is
    placed on ``linspace(0, word.duration_s, n)``. The pen is one point per sample; the path
    written so far is one two-point segment per step, which the default blueprint accumulates
    with a visible time range from the start to the cursor (Rerun's idiom for trails), so the data
    grow linearly with ``n``. Both are sent with one :meth:`~rerun.RecordingStream.send_columns`
    call each. The spoken command is placed on ``time`` *before* the writing (it ends at 0, when
    the pen starts), and also on its own ``audio_time`` timeline starting at 0.

Audio
    The waveform is stored twice: playable, as a WAV :class:`rerun.AssetAudio` (16-bit PCM) shown
    by the blueprint's audio view, and as a plot, as the min/max envelope over buckets of samples
    (:func:`waveform_envelope`, at most ``waveform_points`` rows).

Reading back
    :func:`read_entities`, :func:`recording_summary`, :func:`read_times` and
    :func:`read_component` read a file with :class:`rerun.chunk.RrdReader` (part of
    ``rerun-sdk`` itself since 0.41, no extra needed).
"""

from __future__ import annotations

import colorsys
import errno
import io
import logging
import os
import time
import wave
from collections import defaultdict
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from prg.errors import UsageError
from prg.files import atomic_path
from prg.pipeline.word import WordTrajectory

log = logging.getLogger(__name__)

Y_SIGN = np.array([1.0, -1.0])  # word (x, y up) -> Rerun 2D (x, y down), and back
DECODED_SPACING = 2.5  # normalised letters span [-1, 1]: side by side with a small gap
TIMELINE = "time"
AUDIO_TIMELINE = "audio_time"
FLUSH_TIMEOUT_S = 60.0  # seconds a recording may take to reach its file at the end

PAPER = (255, 255, 255)
INK = (20, 20, 20)
TARGET = (190, 190, 190)
PEN_UP = (150, 150, 150)
PEN = (31, 119, 180)
WAVEFORM = (44, 160, 44)

_INTERNAL_ENTITY_PREFIX = "__"  # Rerun's own entities (recording properties)


# --------------------------------------------------------------------------------------------
# generic helpers: atomic recordings, reading them back
# --------------------------------------------------------------------------------------------
@contextmanager
def recording_stream(
    path: str | os.PathLike,
    application_id: str,
    *,
    recording_id: str | None = None,
    blueprint: rrb.BlueprintLike | None = None,
) -> Iterator[rr.RecordingStream]:
    """A recording stream saving to ``path``, atomically.

    The stream writes to a temporary file next to ``path``; on a clean exit it is flushed,
    closed and renamed to ``path`` (replacing any file there). If the block raises, the
    temporary file is removed, ``path`` is left as it was, and the exception propagates.

    Parameters
    ----------
    path : path-like
        The ``.rrd`` file to write; its folder is created if missing.
    application_id : str
        Rerun application id (recordings of one application share blueprints in the viewer).
    recording_id : str, optional
        Fixed recording id (default: a random one).
    blueprint : rerun.blueprint.BlueprintLike, optional
        Default blueprint stored in the file.

    Yields
    ------
    rerun.RecordingStream
        An explicit stream (not made the global or thread-local default).

    Raises
    ------
    UsageError
        If the file cannot be created (one line naming ``path``).
    """
    path = Path(path)
    rec = rr.RecordingStream(application_id, recording_id=recording_id)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise UsageError(f"{path}: cannot write the recording ({err})") from None
    with atomic_path(path) as tmp:
        try:
            rec.save(tmp, default_blueprint=blueprint)
        except (OSError, RuntimeError) as err:
            raise UsageError(f"{path}: cannot write the recording ({err})") from None
        try:
            yield rec
            try:
                # finite: after a failed write, rerun's flush can wait for its dead writer thread
                # for ever (seen under a file-size limit); a word's recording flushes in < 1 s
                rec.flush(timeout_sec=FLUSH_TIMEOUT_S)
            except (RuntimeError, TimeoutError) as err:  # the file writer failed (a full disk)
                raise OSError(
                    errno.EIO, f"the recording could not be written ({err})", tmp
                ) from err
        finally:
            rec.disconnect()  # closes the file before it is renamed or removed
    log.debug("wrote recording %s", path)


def _chunks(path: str | os.PathLike) -> Iterator:
    """The chunks of the first recording store in ``path`` (blueprints not included)."""
    from rerun.chunk import RrdReader

    path = Path(path)
    if not path.is_file():
        raise UsageError(f"{path}: no such recording file")
    try:
        chunks = list(RrdReader(path).stream().to_chunks())
    except (OSError, ValueError, RuntimeError) as err:
        raise UsageError(f"{path}: not a readable Rerun recording ({err})") from None
    yield from chunks


def _entity(chunk) -> str:
    return chunk.entity_path.lstrip("/")


def read_entities(path: str | os.PathLike) -> dict[str, set[str]]:
    """Entity paths in a recording and the components and archetypes logged on each.

    Parameters
    ----------
    path : path-like
        An ``.rrd`` file.

    Returns
    -------
    dict of str to set of str
        Entity path without the leading ``/`` (as logged, e.g. ``"word/target"``) to the names
        found there: components as ``"Archetype:field"`` (``"LineStrips2D:strips"``) and the
        archetypes' short names (``"LineStrips2D"``). Rerun's own entities (``/__properties``)
        are left out.

    Raises
    ------
    UsageError
        If the file is missing or not a Rerun recording.
    """
    found: dict[str, set[str]] = defaultdict(set)
    for chunk in _chunks(path):
        entity = _entity(chunk)
        if entity.startswith(_INTERNAL_ENTITY_PREFIX):
            continue
        for field in chunk.to_record_batch().schema:
            meta = field.metadata or {}
            if meta.get(rr.RERUN_KIND) != b"data":
                continue
            found[entity].add(meta.get(b"rerun:component", field.name.encode()).decode())
            archetype = meta.get(b"rerun:archetype")
            if archetype:
                found[entity].add(archetype.decode().rsplit(".", 1)[-1])
    return dict(found)


def recording_summary(path: str | os.PathLike) -> dict[str, dict[str, int]]:
    """Row counts per entity and timeline.

    Returns
    -------
    dict of str to dict of str to int
        Entity path (as in :func:`read_entities`) to ``{timeline: rows}``, with static rows
        counted under ``"static"``.
    """
    rows: dict[str, dict[str, int]] = defaultdict(lambda: defaultdict(int))
    for chunk in _chunks(path):
        entity = _entity(chunk)
        if entity.startswith(_INTERNAL_ENTITY_PREFIX):
            continue
        timelines = ["static"] if chunk.is_static else chunk.timeline_names
        for timeline in timelines:
            rows[entity][timeline] += chunk.num_rows
    return {entity: dict(counts) for entity, counts in rows.items()}


def read_times(path: str | os.PathLike, entity: str, timeline: str) -> np.ndarray:
    """The sorted times of an entity's rows on a timeline.

    Returns
    -------
    ndarray, shape (rows,)
        Seconds (float) for duration timelines, raw integers for sequence timelines.
    """
    import pyarrow as pa

    values = []
    for chunk in _chunks(path):
        if _entity(chunk) != entity.lstrip("/") or timeline not in chunk.timeline_names:
            continue
        column = chunk.to_record_batch().column(timeline)
        if pa.types.is_duration(column.type) or pa.types.is_timestamp(column.type):
            values.append(column.cast(pa.int64()).to_numpy() / 1e9)
        else:
            values.append(column.to_numpy())
    return np.sort(np.concatenate(values)) if values else np.empty(0)


def read_component(
    path: str | os.PathLike, entity: str, component: str, timeline: str | None = None
) -> list:
    """The rows of one component of one entity, as Python values.

    Parameters
    ----------
    path : path-like
    entity : str
        As in :func:`read_entities` (a leading ``/`` is ignored).
    component : str
        ``"Archetype:field"``, e.g. ``"Points2D:positions"``.
    timeline : str, optional
        Sort the temporal rows by this timeline (rows not on it keep file order, last).

    Returns
    -------
    list
        One entry per row (each a list of the row's instances): static rows first.
    """
    import pyarrow as pa

    static: list = []
    timed: list[tuple[int, int, object]] = []
    for chunk in _chunks(path):
        if _entity(chunk) != entity.lstrip("/"):
            continue
        batch = chunk.to_record_batch()
        if component not in batch.schema.names:
            continue
        values = batch.column(component).to_pylist()
        if chunk.is_static:
            static.extend(values)
            continue
        if timeline is not None and timeline in chunk.timeline_names:
            keys = batch.column(timeline).cast(pa.int64()).to_pylist()
            rank = 0
        else:
            keys, rank = [0] * len(values), 1
        timed.extend((rank, key, value) for key, value in zip(keys, values))
    if timeline is not None:
        timed.sort(key=lambda row: row[:2])
    return static + [value for _, _, value in timed]


# --------------------------------------------------------------------------------------------
# pure helpers: colours, audio
# --------------------------------------------------------------------------------------------
def distinct_colours(n: int) -> np.ndarray:
    """``n`` clearly different colours (hues a golden angle apart), uint8 RGB, shape (n, 3)."""
    hues = (0.02 + np.arange(n) * 0.618033988749895) % 1.0
    rgb = [colorsys.hsv_to_rgb(h, 0.85, 0.85) for h in hues]
    return np.round(np.array(rgb, dtype=np.float64).reshape(n, 3) * 255).astype(np.uint8)


def _audio_array(audio: np.ndarray) -> np.ndarray:
    """Validated samples, float64 in [-1, 1], shape (n, channels)."""
    samples = np.asarray(audio)
    if samples.ndim == 1:
        samples = samples[:, None]
    if samples.ndim != 2 or samples.shape[0] == 0 or samples.shape[1] == 0:
        raise UsageError(f"audio must have shape (n,) or (n, channels), got {samples.shape}")
    if samples.dtype == np.int16:
        return samples.astype(np.float64) / 32768.0
    if samples.dtype.kind != "f":
        raise UsageError(f"audio samples must be float in [-1, 1] or int16, got {samples.dtype}")
    if not np.all(np.isfinite(samples)):
        raise UsageError("audio samples contain NaN or infinite values")
    return np.clip(samples.astype(np.float64), -1.0, 1.0)


def _sample_rate(sample_rate: int) -> int:
    if isinstance(sample_rate, bool) or int(sample_rate) != sample_rate or sample_rate <= 0:
        raise UsageError(f"sample_rate must be a positive integer (Hz), got {sample_rate!r}")
    return int(sample_rate)


def wav_bytes(audio: np.ndarray, sample_rate: int) -> bytes:
    """Encode samples as a 16-bit PCM WAV file in memory.

    Parameters
    ----------
    audio : ndarray, shape (n,) or (n, channels)
        Float samples in [-1, 1] (clipped, scaled by 32767) or int16 (written as given).
    sample_rate : int
        Hz.

    Returns
    -------
    bytes
    """
    samples = _audio_array(audio)
    raw = np.asarray(audio)
    if raw.dtype == np.int16:  # as given, bit for bit
        pcm = raw.reshape(samples.shape).astype("<i2")
    else:
        pcm = np.round(samples * 32767.0).astype("<i2")
    buffer = io.BytesIO()
    with wave.open(buffer, "wb") as out:
        out.setnchannels(samples.shape[1])
        out.setsampwidth(2)
        out.setframerate(_sample_rate(sample_rate))
        out.writeframes(pcm.tobytes())
    return buffer.getvalue()


def waveform_envelope(
    audio: np.ndarray, sample_rate: int, max_points: int = 2000
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Min/max envelope of a (mono-mixed) waveform over buckets of consecutive samples.

    Parameters
    ----------
    audio : ndarray, shape (n,) or (n, channels)
    sample_rate : int
    max_points : int
        Most buckets returned; the bucket size is ``ceil(n / max_points)`` samples.

    Returns
    -------
    t : ndarray, shape (m,)
        Start time of each bucket (seconds).
    low, high : ndarray, shape (m,)
        Smallest and largest sample of each bucket (equal when a bucket is one sample).
    """
    samples = _audio_array(audio).mean(axis=1)
    rate = _sample_rate(sample_rate)
    if max_points < 1:
        raise UsageError(f"max_points must be at least 1, got {max_points}")
    size = -(-len(samples) // max_points)
    m = -(-len(samples) // size)
    padded = np.concatenate([samples, np.full(m * size - len(samples), samples[-1])])
    buckets = padded.reshape(m, size)
    return np.arange(m) * size / rate, buckets.min(axis=1), buckets.max(axis=1)


# --------------------------------------------------------------------------------------------
# record_write and its parts
# --------------------------------------------------------------------------------------------
def _flip(points: np.ndarray) -> np.ndarray:
    return np.asarray(points, dtype=np.float64) * Y_SIGN


def framing(points: np.ndarray, margin: float = 0.15) -> rrb.VisualBounds2D:
    """2D view bounds around ``points`` (already y-flipped) with a relative margin, so the
    viewer opens on the whole word rather than on its own guess."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    low, high = pts.min(axis=0), pts.max(axis=0)
    pad = margin * max(float((high - low).max()), 1.0)
    return rrb.VisualBounds2D(
        x_range=[low[0] - pad, high[0] + pad], y_range=[low[1] - pad, high[1] + pad]
    )


def _names(chars: Sequence[str]) -> list[str]:
    width = len(str(max(len(chars) - 1, 0)))
    return [f"{i:0{width}d}_{c}" for i, c in enumerate(chars)]


def _images(images, n: int) -> np.ndarray:
    """Letter images as uint8, shape (n, h, w)."""
    arr = np.asarray(images)
    if arr.ndim == 4 and arr.shape[1] == 1:
        arr = arr[:, 0]
    if arr.ndim != 3 or arr.shape[0] != n:
        raise UsageError(
            f"images must have shape ({n}, H, W) or ({n}, 1, H, W) for the {n} letters, "
            f"got {arr.shape}"
        )
    if arr.dtype == np.uint8:
        return arr
    if arr.dtype.kind != "f" or not np.all(np.isfinite(arr)):
        raise UsageError("images must be uint8 or finite floats in [0, 1]")
    return np.round(np.clip(arr.astype(np.float64), 0.0, 1.0) * 255).astype(np.uint8)


def _decoded(letters, n: int) -> np.ndarray:
    arr = np.asarray(letters, dtype=np.float64)
    if arr.ndim != 3 or arr.shape[0] != n or arr.shape[2] != 2 or arr.shape[1] < 2:
        raise UsageError(
            f"letters must have shape ({n}, k, 2) for the {n} letters, got {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise UsageError("letters contain NaN or infinite values")
    return arr


def _rollout(rollout) -> np.ndarray:
    arr = np.asarray(rollout, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] < 2:
        raise UsageError(f"rollout must have shape (n, 2) with n >= 2, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise UsageError("rollout contains NaN or infinite values")
    return arr


def log_audio(
    rec: rr.RecordingStream,
    audio: np.ndarray,
    sample_rate: int,
    *,
    entity: str = "inputs/audio",
    waveform_entity: str = "inputs/waveform",
    waveform_points: int = 2000,
) -> float:
    """Log a spoken command: playable WAV asset and min/max waveform plot.

    Both sit on ``audio_time`` (from 0) and on ``time``, ending at 0 (the speech precedes the
    writing). Returns the audio's duration in seconds.
    """
    rate = _sample_rate(sample_rate)
    samples = _audio_array(audio)
    duration = samples.shape[0] / rate
    rec.send_columns(
        entity,
        indexes=[
            rr.TimeColumn(AUDIO_TIMELINE, duration=[0.0]),
            rr.TimeColumn(TIMELINE, duration=[-duration]),
        ],
        columns=rr.AssetAudio.columns(blob=[wav_bytes(audio, rate)], media_type=["audio/wav"]),
        strict=True,
    )
    t, low, high = waveform_envelope(samples, rate, waveform_points)
    one = np.array_equal(low, high)
    rec.log(
        waveform_entity,
        rr.SeriesLines(
            colors=[WAVEFORM] if one else [WAVEFORM, WAVEFORM],
            names=["amplitude"] if one else ["min", "max"],
        ),
        static=True,
        strict=True,
    )
    if one:
        scalars = rr.Scalars.columns(scalars=low)
    else:
        scalars = rr.Scalars.columns(scalars=np.column_stack([low, high]).reshape(-1))
        scalars = scalars.partition(np.full(len(t), 2))
    rec.send_columns(
        waveform_entity,
        indexes=[
            rr.TimeColumn(AUDIO_TIMELINE, duration=t),
            rr.TimeColumn(TIMELINE, duration=t - duration),
        ],
        columns=scalars,
        strict=True,
    )
    return duration


def log_word(rec: rr.RecordingStream, word: WordTrajectory, root: str = "word") -> None:
    """Log the word's static geometry: letters, connections, pen-up travel, target path.

    Letters are drawn in one ink colour, each connection in its own colour
    (:func:`distinct_colours`); connection and pen-up strips include the neighbouring letters'
    end points so the ink is continuous. Positions are y-flipped (module docstring).
    """
    chars = [c for c in word.text if c != " "]
    names = _names(chars)
    kinds = word.segment_kinds
    n_connections = kinds.count("connection")
    colours = distinct_colours(n_connections)
    rec.log(
        f"{root}/target",
        rr.LineStrips2D(
            [_flip(word.points)],
            colors=[TARGET],
            radii=rr.Radius.ui_points(4.0),
            labels=["target"],
            show_labels=False,
            draw_order=1.0,
        ),
        static=True,
        strict=True,
    )
    counters = {"letter": 0, "connection": 0, "space": 0}
    for k, kind in enumerate(kinds):
        i = counters[kind]
        counters[kind] += 1
        pts = word.segment_points(k)
        if kind == "letter":
            rec.log(
                f"{root}/letters/{names[i]}",
                rr.LineStrips2D(
                    [_flip(pts)],
                    colors=[INK],
                    radii=rr.Radius.ui_points(1.5),
                    labels=[chars[i]],
                    show_labels=False,
                    draw_order=10.0,
                ),
                static=True,
                strict=True,
            )
            continue
        ends = [word.segment_points(k - 1)[-1:], pts, word.segment_points(k + 1)[:1]]
        if kind == "connection":
            entity, colour, radius, order = f"{root}/connections/{i}", colours[i], 1.5, 11.0
        else:
            entity, colour, radius, order = f"{root}/pen_up/{i}", PEN_UP, 0.75, 2.0
        rec.log(
            entity,
            rr.LineStrips2D(
                [_flip(np.concatenate(ends))],
                colors=[colour],
                radii=rr.Radius.ui_points(radius),
                draw_order=order,
            ),
            static=True,
            strict=True,
        )


def log_rollout(
    rec: rr.RecordingStream, rollout: np.ndarray, duration_s: float, root: str = "word/rollout"
) -> np.ndarray:
    """Animate the DMP rollout on ``time``: pen point per sample, path segment per step.

    Two :meth:`~rerun.RecordingStream.send_columns` calls: ``<root>/pen`` gets one point per
    sample at ``linspace(0, duration_s, n)``; ``<root>/path`` gets the segment from sample
    ``i - 1`` to ``i`` at sample ``i``'s time (``n - 1`` rows), drawn accumulated by the
    blueprint. Returns the time grid, shape (n,).
    """
    pts = _flip(_rollout(rollout))
    t = np.linspace(0.0, float(duration_s), len(pts))
    rec.log(
        f"{root}/pen",
        rr.Points2D.from_fields(colors=[PEN], radii=rr.Radius.ui_points(6.0), draw_order=30.0),
        static=True,
        strict=True,
    )
    rec.send_columns(
        f"{root}/pen",
        indexes=[rr.TimeColumn(TIMELINE, duration=t)],
        columns=rr.Points2D.columns(positions=pts),
        strict=True,
    )
    rec.log(
        f"{root}/path",
        rr.LineStrips2D.from_fields(colors=[PEN], radii=rr.Radius.ui_points(2.0), draw_order=20.0),
        static=True,
        strict=True,
    )
    rec.send_columns(
        f"{root}/path",
        indexes=[rr.TimeColumn(TIMELINE, duration=t[1:])],
        columns=rr.LineStrips2D.columns(strips=np.stack([pts[:-1], pts[1:]], axis=1)),
        strict=True,
    )
    return t


def log_decoded(rec: rr.RecordingStream, letters: np.ndarray, names: Sequence[str]) -> None:
    """Raw normalised decoded letters under ``decoded/<name>``, side by side (y-flipped)."""
    for i, (name, pts) in enumerate(zip(names, letters)):
        rec.log(
            f"decoded/{name}",
            rr.Transform3D(translation=[DECODED_SPACING * i, 0.0, 0.0]),
            rr.LineStrips2D(
                [_flip(pts)], colors=[INK], radii=rr.Radius.ui_points(1.5), labels=[name[-1]]
            ),
            static=True,
            strict=True,
        )


def _summary(word: WordTrajectory, n_samples: int) -> str:
    kinds = word.segment_kinds
    lines = [
        f"# {word.text}",
        "",
        f"- letters: {kinds.count('letter')}, connections: {kinds.count('connection')}, "
        f"pen-up travels: {kinds.count('space')}",
        f"- points: {len(word.points)}, path length: {word.path_length:.2f} cm",
        f"- duration: {word.duration_s:.2f} s at {word.speed_cm_s:g} cm/s mean speed",
        f"- DMP rollout: {n_samples} samples",
    ]
    if word.dmp:
        lines.append(f"- DMP basis functions: {word.dmp.get('n_basis', '?')}")
    lines.append("- coordinates: cm, logged as (x, -y) so the word reads upright")
    return "\n".join(lines) + "\n"


def write_blueprint(
    word: WordTrajectory,
    *,
    image_names: Sequence[str] = (),
    audio: bool = False,
    transcript: bool = False,
    decoded: bool = False,
) -> rrb.Blueprint:
    """The default layout: the word (with the growing rollout path) beside the inputs.

    The word view has a white background (paper) and shows ``word/rollout/path`` accumulated
    from the start of ``time`` to the cursor; the time panel opens on ``time``.
    """
    trail = rrb.VisibleTimeRanges(
        timeline=TIMELINE,
        start=rrb.TimeRangeBoundary.infinite(),
        end=rrb.TimeRangeBoundary.cursor_relative(),
    )
    word_view = rrb.Spatial2DView(
        origin="word",
        name=f"Word: {word.text}",
        background=PAPER,
        visual_bounds=framing(_flip(word.points)),
        overrides={"word/rollout/path": [trail, rr.LineStrips2D.from_fields().visualizer()]},
    )
    left = [word_view]
    if decoded:
        left.append(rrb.Spatial2DView(origin="decoded", name="Decoded letters", background=PAPER))
    right: list = []
    if transcript:
        right.append(rrb.TextDocumentView(origin="inputs/transcript", name="Transcript"))
    if audio:
        right.append(rrb.AudioView(origin="inputs/audio", name="Audio"))
        right.append(rrb.TimeSeriesView(origin="inputs/waveform", name="Waveform"))
    if image_names:
        right.append(
            rrb.Grid(
                *[rrb.Spatial2DView(origin=f"inputs/images/{n}", name=n) for n in image_names],
                name="Letter images",
            )
        )
    right.append(rrb.TextDocumentView(origin="summary", name="Summary"))
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(*left, row_shares=[3, 1][: len(left)]),
            rrb.Vertical(*right),
            column_shares=[3, 1],
        ),
        rrb.TimePanel(timeline=TIMELINE),
        collapse_panels=False,
    )


def record_write(
    path: str | os.PathLike,
    word: WordTrajectory,
    rollout: np.ndarray,
    *,
    letters: np.ndarray | None = None,
    images: np.ndarray | None = None,
    audio: np.ndarray | None = None,
    sample_rate: int = 16000,
    transcript: str | None = None,
    application_id: str = "prg-write",
    waveform_points: int = 2000,
) -> Path:
    """Record a written word, its inputs and its DMP rollout to an ``.rrd`` file, atomically.

    Entity paths, timelines and the y-flip are described in the module docstring.

    Parameters
    ----------
    path : path-like
        The ``.rrd`` file.
    word : WordTrajectory
        The generated word (:func:`prg.pipeline.generate.write_word`).
    rollout : ndarray, shape (n, 2)
        The DMP rollout in centimetres, on ``linspace(0, word.duration_s, n)``.
    letters : ndarray, shape (N, k, 2), optional
        Raw normalised decoded letters (y up), one per non-space character of ``word.text``.
    images : ndarray, shape (N, H, W) or (N, 1, H, W), optional
        Letter images, floats in [0, 1] or uint8, one per letter.
    audio : ndarray, shape (s,) or (s, channels), optional
        The spoken command: float samples in [-1, 1] or int16.
    sample_rate : int
        Of ``audio`` (Hz).
    transcript : str, optional
        What the speech recogniser heard (or the typed text).
    application_id : str
    waveform_points : int
        Most rows of the waveform plot.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    UsageError
        On inputs of the wrong shape or type (nothing is written).
    """
    start = time.perf_counter()
    chars = [c for c in word.text if c != " "]
    names = _names(chars)
    pts = _rollout(rollout)
    imgs = None if images is None else _images(images, len(chars))
    raw = None if letters is None else _decoded(letters, len(chars))
    if audio is not None:
        _audio_array(audio)
        _sample_rate(sample_rate)
        if isinstance(waveform_points, bool) or int(waveform_points) < 1:
            raise UsageError(f"waveform_points must be at least 1, got {waveform_points!r}")
    if transcript is not None and not isinstance(transcript, str):
        raise UsageError(f"transcript must be a string, got {type(transcript).__name__}")
    blueprint = write_blueprint(
        word,
        image_names=names if imgs is not None else (),
        audio=audio is not None,
        transcript=transcript is not None,
        decoded=raw is not None,
    )
    with recording_stream(path, application_id, blueprint=blueprint) as rec:
        rec.log(
            "summary",
            rr.TextDocument(_summary(word, len(pts)), media_type="text/markdown"),
            static=True,
            strict=True,
        )
        if transcript is not None:
            rec.log("inputs/transcript", rr.TextDocument(transcript), static=True, strict=True)
        if audio is not None:
            log_audio(rec, audio, sample_rate, waveform_points=waveform_points)
        if imgs is not None:
            for name, image in zip(names, imgs):
                rec.log(f"inputs/images/{name}", rr.Image(image), static=True, strict=True)
        if raw is not None:
            log_decoded(rec, raw, names)
        log_word(rec, word)
        log_rollout(rec, pts, word.duration_s)
    log.info(
        "recorded %r to %s in %.0f ms (%d rollout samples)",
        word.text,
        path,
        (time.perf_counter() - start) * 1000,
        len(pts),
    )
    return Path(path)
