"""A handwritten word as the study draws it: :class:`Sample`, its strokes and delayed strokes."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from prg.errors import UsageError

ROBOT = "robot"  #: the writer id of robot samples (studies.design's trials use it too)
#: The capture page's rule (``capture.delayed_max_size``): a stroke after the word is a delayed
#: stroke (a dot or a bar) when its bounding box is no taller than this fraction of the word
#: stroke's height and no wider than twice it; a larger one is a pen lift.
DELAYED_MAX_SIZE = 0.35


@dataclass(frozen=True)
class Sample:
    """One handwritten word.

    Attributes
    ----------
    word : str
    writer_id : str
        ``"robot"`` for the robot's sample.
    strokes : tuple of ndarray, each shape (n_i, 2)
        Pen-down strokes in writing order, y up, any unit.
    origin : str
        The file it came from.
    lifted : bool
        The writer lifted the pen (a capture flagged so, or strokes after the first that are
        not delayed strokes).
    delayed : tuple of int
        Indices into ``strokes`` of the delayed strokes: the dots and bars written after the
        word (the robot's marks; the strokes a capture kept as such). Never 0.
    """

    word: str
    writer_id: str
    strokes: tuple[np.ndarray, ...]
    origin: str = ""
    lifted: bool = False
    delayed: tuple[int, ...] = ()

    @property
    def source(self) -> str:
        """``"robot"`` or ``"human"``."""
        return ROBOT if self.writer_id == ROBOT else "human"

    def without_delayed(self) -> Sample:
        """The sample without its delayed strokes (the paper's single stroke)."""
        if not self.delayed:
            return self
        keep = tuple(s for i, s in enumerate(self.strokes) if i not in self.delayed)
        return replace(self, strokes=keep, delayed=())


def _identity_from_path(path: Path, root: Path) -> tuple[str | None, str | None]:
    """(word, writer_id) from ``<root>/.../<writer_id>/<word>.<ext>``."""
    rel = path.relative_to(root)
    writer = rel.parts[-2] if len(rel.parts) >= 2 else None
    return path.stem, writer


def _need(writer: str | None, where: str) -> str:
    if not writer:
        raise UsageError(
            f"{where}: no writer_id: put it in the file or name the file <writer_id>/<word>.json"
        )
    return str(writer)
