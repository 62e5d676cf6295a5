"""Stimuli: robot and human handwriting samples, read from their files and drawn alike.

Every sample — the robot's ``prg-write`` word trajectory or a person's pen trajectory — becomes a
:class:`Sample` (strokes of points, y up, any unit) and is drawn by one renderer,
:func:`render_sample`, with one :class:`RenderStyle`: the same PNG size, margins and stroke width,
black ink on white, the word scaled to the same ink height (or width, when it is too wide) and
centred, so that nothing but the shape of the handwriting tells the samples apart (pressure,
timing and colour are dropped).

Human sample files (:func:`load_human_samples`, any mix, searched recursively):

* **capture JSON** written by the capture page (schema ``prg.handwriting_capture``, version 1): a
  writer's session, one entry per word; strokes of ``[x, y, t_ms, pressure]`` in CSS pixels,
  y down (see ``studies/web/capture.js``); ``delayed`` (optional: files from before it have
  none) lists the strokes the page kept as delayed strokes;
* **strokes JSON**: ``{"word": ..., "writer_id": ..., "strokes": [[[x, y], ...], ...],
  "y_down": true, "delayed": [1]}`` (``word``/``writer_id`` may come from the path, below;
  extra numbers per point are ignored; ``delayed`` is optional), or a ``prg.word_trajectory``
  file;
* **SVG**: the ``polyline``, ``polygon``, ``line`` and ``path`` elements, with their
  ``transform`` attributes, read by vpype (:mod:`studies.stimuli.svg`: curves and arcs sampled
  finely, in the file's user units).

A file without ``word``/``writer_id`` inside is named ``<writer_id>/<word>.json|svg``.

**Delayed strokes.** The word is one movement; the dots of the i's and j's and the bars of the
t's and f's may follow it as separate, small strokes (a :class:`Sample`'s ``delayed``). A sample
whose strokes after the first are all delayed strokes was not written with a pen lift; any
other extra stroke is a lift. The robot's marks (``"mark"`` segments of its word trajectory)
are its delayed strokes. A study's ``delayed_strokes`` setting decides for both: with False,
the delayed strokes of every sample are left undrawn (the paper's single stroke).

Robot samples: :func:`generate_robot_words` writes each word with :class:`prg.writer.Writer`
(``prg-write``'s settings, :mod:`studies.stimuli.write_settings`); :func:`load_robot_words`
reads ``<word>.json`` or ``<word>/word.json`` word trajectories.

One concept a module: :mod:`~studies.stimuli.sample`, :mod:`~studies.stimuli.render`,
:mod:`~studies.stimuli.json_samples`, :mod:`~studies.stimuli.svg`,
:mod:`~studies.stimuli.trajectories`, :mod:`~studies.stimuli.human`,
:mod:`~studies.stimuli.pilot`, :mod:`~studies.stimuli.robot` and
:mod:`~studies.stimuli.write_settings`.
"""

from __future__ import annotations

from studies.stimuli.human import HUMAN_SUFFIXES, HumanSamples, load_human_samples
from studies.stimuli.json_samples import (
    CAPTURE_SCHEMA,
    CAPTURE_VERSION,
    WORD_SCHEMA,
    is_lifted,
    read_capture,
    read_json_sample,
)
from studies.stimuli.pilot import held_out_words, stand_ins
from studies.stimuli.render import (
    MAX_RENDER_PIXELS,
    MAX_RENDER_PX,
    RenderStyle,
    fit_transform,
    render_sample,
    render_strokes,
    save_png,
    stimulus_name,
    to_pixels,
)
from studies.stimuli.robot import checkpoint, generate_robot_words, load_robot_words, unmarked_words
from studies.stimuli.sample import DELAYED_MAX_SIZE, ROBOT, Sample
from studies.stimuli.svg import path_strokes, read_svg
from studies.stimuli.trajectories import trajectory_sample, word_strokes
from studies.stimuli.write_settings import WriteSettings, sets_delayed_strokes, write_settings

__all__ = [
    "CAPTURE_SCHEMA",
    "CAPTURE_VERSION",
    "DELAYED_MAX_SIZE",
    "HUMAN_SUFFIXES",
    "MAX_RENDER_PIXELS",
    "MAX_RENDER_PX",
    "ROBOT",
    "WORD_SCHEMA",
    "HumanSamples",
    "RenderStyle",
    "Sample",
    "WriteSettings",
    "checkpoint",
    "fit_transform",
    "generate_robot_words",
    "held_out_words",
    "is_lifted",
    "load_human_samples",
    "load_robot_words",
    "path_strokes",
    "read_capture",
    "read_json_sample",
    "read_svg",
    "render_sample",
    "render_strokes",
    "save_png",
    "sets_delayed_strokes",
    "stand_ins",
    "stimulus_name",
    "to_pixels",
    "trajectory_sample",
    "unmarked_words",
    "word_strokes",
    "write_settings",
]
