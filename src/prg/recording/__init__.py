"""Rerun recordings (``.rrd``): how they are written, read back, and the two the project makes.

Modules
-------
:mod:`prg.recording.stream`
    :func:`recording_stream`: an explicit stream saving to a file atomically (a reader never
    sees half a file, an error leaves nothing behind). ``rerun FILE.rrd`` opens the result.
:mod:`prg.recording.read`
    :func:`read_entities`, :func:`recording_summary`, :func:`read_times`,
    :func:`read_component` and :func:`read_views` (the default blueprint's views) read a file
    back (the tests use them).
:mod:`prg.recording.views`
    What both recordings share in the viewer: the y-flip of 2D positions (:data:`Y_SIGN`),
    the framing of views on their data (:func:`framing`, :func:`framing_eye`), animated points
    and growing paths.
:mod:`prg.recording.audio`
    Audio as a 16-bit PCM WAV (:func:`wav_bytes`) and its min/max envelope
    (:func:`waveform_envelope`).
:mod:`prg.recording.word`
    :func:`record_write`: a written word with its inputs and animated DMP rollout (``word.rrd``,
    ``prg-write``).
:mod:`prg.recording.simulation`
    :func:`record_simulation`: the simulated robot writing a word (``sim.rrd``,
    ``prg-simulate``).

Colours come from the one palette, :mod:`prg.plotting`.
"""

from __future__ import annotations

from prg.plotting import distinct_colours
from prg.recording.audio import wav_bytes, waveform_envelope
from prg.recording.read import (
    read_component,
    read_entities,
    read_times,
    read_views,
    recording_summary,
)
from prg.recording.simulation import (
    SIM_TIMELINE,
    record_simulation,
    recording_urdf,
    sim_blueprint,
)
from prg.recording.stream import FLUSH_TIMEOUT_S, recording_stream
from prg.recording.views import Y_SIGN, framing, framing_eye
from prg.recording.word import (
    AUDIO_TIMELINE,
    DECODED_SPACING,
    TIMELINE,
    log_audio,
    log_decoded,
    log_rollout,
    log_word,
    record_write,
    write_blueprint,
)

__all__ = [
    "AUDIO_TIMELINE",
    "DECODED_SPACING",
    "FLUSH_TIMEOUT_S",
    "SIM_TIMELINE",
    "TIMELINE",
    "Y_SIGN",
    "distinct_colours",
    "framing",
    "framing_eye",
    "log_audio",
    "log_decoded",
    "log_rollout",
    "log_word",
    "read_component",
    "read_entities",
    "read_times",
    "read_views",
    "record_simulation",
    "record_write",
    "recording_stream",
    "recording_summary",
    "recording_urdf",
    "sim_blueprint",
    "wav_bytes",
    "waveform_envelope",
    "write_blueprint",
]
