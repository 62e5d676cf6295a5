"""The Rerun recording of a written word (``word.rrd``): :func:`record_write`.

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
``word/pen_up/<k>``             LineStrips2D        static, pen-up travel (between words, to a mark)
``word/marks/<m>``              LineStrips2D        static, a delayed stroke (i/j dot, t/f bar)
``word/target``                 LineStrips2D        static, the demonstration path of the DMP
``word/rollout/pen``            Points2D            one row per motion sample on ``time``
``word/rollout/path``           LineStrips2D        one segment per pen-down step on ``time``
``summary``                     TextDocument        static (text, sizes, timing, DMP)
==============================  ==================  ===============================================

``<i>`` is the letter's index (zero-padded to the width of the largest index), ``<c>`` its
character, ``<j>``/``<k>`` the connection's / pen-up travel's index.

Coordinates
    Word coordinates are centimetres with y up (:class:`~prg.pipeline.word.WordTrajectory`),
    logged as ``(x, -y)`` (:mod:`prg.recording.views`). The raw decoded letters (normalised
    units, y up) are flipped the same way and set side by side with a
    :class:`rerun.Transform3D` translation of :data:`DECODED_SPACING` units per letter.

Timelines
    ``time`` (seconds, a duration timeline) is the writing: the body's DMP rollout of ``n``
    samples is placed on ``linspace(0, dmp.tau, n)``, then the delayed strokes and the pen-up
    travels to them follow (:func:`prg.pipeline.timing.delayed_samples`, same spacing). The pen is
    one point per sample; the ink written so far is one two-point segment per pen-down step
    (none over a pen-up travel), which the default blueprint accumulates
    with a visible time range from the start to the cursor (Rerun's idiom for trails), so the data
    grow linearly with ``n``. Both are sent with one :meth:`~rerun.RecordingStream.send_columns`
    call each. The spoken command is placed on ``time`` *before* the writing (it ends at 0, when
    the pen starts), and also on its own ``audio_time`` timeline starting at 0.

Audio
    The waveform is stored twice: playable, as a WAV :class:`rerun.AssetAudio` (16-bit PCM) shown
    by the blueprint's audio view, and as a plot, as the min/max envelope over buckets of samples
    (:func:`~prg.recording.audio.waveform_envelope`, at most ``waveform_points`` rows).
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from prg.errors import UsageError
from prg.pipeline.word import PEN_UP_KINDS, WordTrajectory
from prg.plotting import INK, PAPER, PEN, PEN_UP, TARGET, WAVEFORM, distinct_colours
from prg.recording.audio import audio_samples, sample_rate_hz, wav_bytes, waveform_envelope
from prg.recording.stream import recording_stream
from prg.recording.views import accumulated, flip, framing, log_columns, segments

log = logging.getLogger("prg.recording")

DECODED_SPACING = 2.5  # normalised letters span [-1, 1]: side by side with a small gap
TIMELINE = "time"
AUDIO_TIMELINE = "audio_time"


# --------------------------------------------------------------------------------------------
# validated inputs
# --------------------------------------------------------------------------------------------
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


def _motion(word: WordTrajectory, rollout: np.ndarray) -> tuple[np.ndarray, ...]:
    """The body's rollout on its time grid, then the delayed strokes at the same spacing:
    samples, times, pen-down flags."""
    from prg.pipeline.motion import pen_down_samples
    from prg.pipeline.timing import delayed_samples, stroke_duration

    if word.dmp is not None:
        tau = word.dmp.tau
    else:
        delayed = word.delayed_strokes()
        tau = word.duration_s - sum(stroke_duration(p, word.speed_cm_s) for _, p in delayed)
    after_xy, after_t, after_down = delayed_samples(word, tau / (len(rollout) - 1))
    body = slice(0, word.body_end)
    down = pen_down_samples(word.points[body], word.segment[body], word.segment_kinds, rollout)
    return (
        np.concatenate([rollout, after_xy]),
        np.concatenate([np.linspace(0.0, tau, len(rollout)), tau + after_t]),
        np.concatenate([down, after_down]),
    )


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
    rate = sample_rate_hz(sample_rate)
    samples = audio_samples(audio)
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
            [flip(word.points)],
            colors=[TARGET],
            radii=rr.Radius.ui_points(4.0),
            labels=["target"],
            show_labels=False,
            draw_order=1.0,
        ),
        static=True,
        strict=True,
    )
    counters = {"letter": 0, "connection": 0, "pen_up": 0, "mark": 0}
    for k, kind in enumerate(kinds):
        counter = "pen_up" if kind in PEN_UP_KINDS else kind
        i = counters[counter]
        counters[counter] += 1
        pts = word.segment_points(k)
        if kind in ("letter", "mark"):
            rec.log(
                f"{root}/letters/{names[i]}" if kind == "letter" else f"{root}/marks/{i}",
                rr.LineStrips2D(
                    [flip(pts)],
                    colors=[INK],
                    radii=rr.Radius.ui_points(1.5),
                    labels=[chars[i] if kind == "letter" else "mark"],
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
                [flip(np.concatenate(ends))],
                colors=[colour],
                radii=rr.Radius.ui_points(radius),
                draw_order=order,
            ),
            static=True,
            strict=True,
        )


def log_rollout(
    rec: rr.RecordingStream,
    samples: np.ndarray,
    t: np.ndarray,
    pen_down: np.ndarray,
    root: str = "word/rollout",
) -> None:
    """Animate the word's motion on ``time``: pen point per sample, ink segment per step.

    Two :meth:`~rerun.RecordingStream.send_columns` calls: ``<root>/pen`` gets one point per
    sample at ``t``; ``<root>/path`` gets the segment from sample ``i - 1`` to ``i`` at sample
    ``i``'s time where both are pen-down, drawn accumulated by the blueprint.
    """
    pts = flip(samples)
    inked = np.flatnonzero(pen_down[1:] & pen_down[:-1]) + 1
    log_columns(
        rec,
        f"{root}/pen",
        rr.Points2D.from_fields(colors=[PEN], radii=rr.Radius.ui_points(6.0), draw_order=30.0),
        TIMELINE,
        t,
        rr.Points2D.columns(positions=pts),
        strict=True,
    )
    log_columns(
        rec,
        f"{root}/path",
        rr.LineStrips2D.from_fields(colors=[PEN], radii=rr.Radius.ui_points(2.0), draw_order=20.0),
        TIMELINE,
        t[inked],
        rr.LineStrips2D.columns(strips=segments(pts)[inked - 1]),
        strict=True,
    )


def _decoded_strip(letters: np.ndarray) -> np.ndarray:
    """The decoded letters' points where the strip shows them: y-flipped, letter ``i`` moved
    ``DECODED_SPACING * i`` to the right; shape (N, k, 2)."""
    shift = np.zeros((len(letters), 1, 2))
    shift[:, 0, 0] = DECODED_SPACING * np.arange(len(letters))
    return flip(letters) + shift


def log_decoded(rec: rr.RecordingStream, letters: np.ndarray, names: Sequence[str]) -> None:
    """Raw normalised decoded letters under ``decoded/<name>``, side by side (y-flipped)."""
    for i, (name, pts) in enumerate(zip(names, letters)):
        rec.log(
            f"decoded/{name}",
            rr.Transform3D(translation=[DECODED_SPACING * i, 0.0, 0.0]),
            rr.LineStrips2D(
                [flip(pts)], colors=[INK], radii=rr.Radius.ui_points(1.5), labels=[name[-1]]
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
        f"delayed strokes: {kinds.count('mark')}, "
        f"pen-up travels: {sum(kind in PEN_UP_KINDS for kind in kinds)}",
        f"- points: {len(word.points)}, path length: {word.path_length:.2f} cm",
        f"- duration: {word.duration_s:.2f} s at {word.speed_cm_s:g} cm/s mean speed",
        f"- motion: {n_samples} samples (the body's DMP rollout, then the delayed strokes)",
    ]
    if word.dmp is not None:
        lines.append(f"- DMP basis functions: {word.dmp.n_basis}")
    lines.append("- coordinates: cm, logged as (x, -y) so the word reads upright")
    return "\n".join(lines) + "\n"


def write_blueprint(
    word: WordTrajectory,
    *,
    image_names: Sequence[str] = (),
    audio: bool = False,
    transcript: bool = False,
    decoded: np.ndarray | None = None,
) -> rrb.Blueprint:
    """The default layout: the word (with the growing rollout path) beside the inputs.

    The word view has a white background (paper) and shows ``word/rollout/path`` accumulated
    from the start of ``time`` to the cursor; it and the strip of ``decoded`` letters (shape
    (N, k, 2), when given) open on bounds around their points with a margin, so every letter
    is whole. The side panels start collapsed, the time panel as its playback bar on ``time``.
    """
    word_view = rrb.Spatial2DView(
        origin="word",
        name=f"Word: {word.text}",
        background=PAPER,
        visual_bounds=framing(flip(word.points)),
        overrides={"word/rollout/path": accumulated(TIMELINE)},
    )
    left = [word_view]
    if decoded is not None:
        left.append(
            rrb.Spatial2DView(
                origin="decoded",
                name="Decoded letters",
                background=PAPER,
                visual_bounds=framing(_decoded_strip(decoded), margin=0.1),
            )
        )
    right: list = []
    if transcript:
        right.append(rrb.TextDocumentView(origin="inputs/transcript", name="Transcript"))
    if audio:
        right.append(rrb.AudioView(origin="inputs/audio", name="Audio"))
        right.append(
            rrb.TimeSeriesView(
                origin="inputs/waveform",
                name="Waveform",
                plot_legend=rrb.PlotLegend(visible=False),  # min and max: one colour, no key
            )
        )
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
        rrb.TimePanel(timeline=TIMELINE, state="collapsed"),
        collapse_panels=True,
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
        The body's DMP rollout in centimetres, on ``linspace(0, word.dmp.tau, n)`` (without a
        DMP: on ``linspace(0, body duration, n)``); the delayed strokes are added to it.
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
    pts, t, down = _motion(word, _rollout(rollout))
    imgs = None if images is None else _images(images, len(chars))
    raw = None if letters is None else _decoded(letters, len(chars))
    if audio is not None:
        audio_samples(audio)
        sample_rate_hz(sample_rate)
        if isinstance(waveform_points, bool) or int(waveform_points) < 1:
            raise UsageError(f"waveform_points must be at least 1, got {waveform_points!r}")
    if transcript is not None and not isinstance(transcript, str):
        raise UsageError(f"transcript must be a string, got {type(transcript).__name__}")
    blueprint = write_blueprint(
        word,
        image_names=names if imgs is not None else (),
        audio=audio is not None,
        transcript=transcript is not None,
        decoded=raw,
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
        log_rollout(rec, pts, t, down)
    log.info(  # the file's name only: callers may write into a staging folder, renamed later
        "recorded %r as %s in %.0f ms (%d rollout samples)",
        word.text,
        Path(path).name,
        (time.perf_counter() - start) * 1000,
        len(pts),
    )
    return Path(path)
