"""prg: Perceive-Represent-Generate, from multimodal commands to robot handwriting.

The paper's path in three lines (a trained model from ``make demo``)::

    from prg import Writer, simulate_word
    result = Writer.from_checkpoint("models/muse/model.ckpt").write(text="joy")
    robot = simulate_word(result.word, "panda")

:class:`Writer` (``prg.writer``) perceives a command given through any subset of channels
(text, sound, letter images, pen trajectories), decodes a trajectory per letter and composes the
word with one DMP; :func:`simulate_word` (``prg.sim``) has a simulated arm write it. The names
are imported on first use, so ``import prg`` stays light (no torch, no PyBullet).
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

_PUBLIC = {
    "Writer": "prg.writer",
    "WriteResult": "prg.writer",
    "Perception": "prg.writer",
    "simulate_word": "prg.sim",
}

__all__ = ["__version__", *_PUBLIC]


def __getattr__(name: str) -> Any:
    if name not in _PUBLIC:
        raise AttributeError(f"module 'prg' has no attribute {name!r}")
    return getattr(importlib.import_module(_PUBLIC[name]), name)
