"""Raw handwriting samples as read from a source (UJI file or the synthetic generator)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class RawSample:
    """One handwritten character as recorded, before any preprocessing.

    Attributes
    ----------
    char : str
        The character written (any Unicode character; filtering to the 62 classes happens later).
    writer : str
        Writer id, stable across the writer's sessions (e.g. ``"trn_UJI_W03"``); splits group by it.
    session : str
        Session id as given by the source (e.g. ``"trn_UJI_W03-01"``).
    strokes : list of ndarray, each shape (k, 2)
        Pen-down strokes in source coordinates, **y axis pointing down** (tablet and Hershey
        convention); preprocessing flips it.
    source : str
        ``"uji"`` or ``"synthetic"``.
    line : int
        1-based line number of the entry's ``WORD`` line in its file (0 when not from a file).
    """

    char: str
    writer: str
    session: str
    strokes: list[np.ndarray] = field(repr=False)
    source: str
    line: int = 0

    @property
    def num_strokes(self) -> int:
        return len(self.strokes)
