"""Word trajectories (``prg-write``'s :class:`prg.pipeline.word.WordTrajectory`) as samples:
their pen-down runs, the marks after the body as delayed strokes."""

from __future__ import annotations

import numpy as np

from studies.stimuli.sample import Sample


def _pen_down_runs(traj) -> list[tuple[int, int]]:
    """``(start, stop)`` point indices of each pen-down run of a word trajectory."""
    down = traj.pen_down()
    out, start = [], None
    for i, d in enumerate([*down.tolist(), False]):
        if d and start is None:
            start = i
        elif not d and start is not None:
            out.append((start, i))
            start = None
    return out


def word_strokes(traj) -> tuple[np.ndarray, ...]:
    """The ink of a :class:`prg.pipeline.word.WordTrajectory`: its pen-down runs (y up), the
    delayed strokes (its ``"mark"`` segments) included."""
    return tuple(traj.points[a:b].copy() for a, b in _pen_down_runs(traj))


def trajectory_sample(traj, writer_id: str, origin: str) -> Sample:
    """A word trajectory as a :class:`Sample`: its pen-down runs, the runs after the body
    (:attr:`~prg.pipeline.word.WordTrajectory.body_end`: the marks) as its delayed strokes."""
    runs = _pen_down_runs(traj)
    strokes = tuple(traj.points[a:b].copy() for a, b in runs)
    delayed = tuple(i for i, (a, _) in enumerate(runs) if i and a >= traj.body_end)
    return Sample(traj.text, writer_id, strokes, origin, False, delayed)
