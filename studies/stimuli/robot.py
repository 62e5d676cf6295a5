"""The robot's samples: its words written with :class:`prg.writer.Writer` (the model loaded
once, the study's settings as :class:`~prg.pipeline.compose.GenerateSettings`), or read from
``prg-write``'s word trajectories."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path

from prg.errors import UsageError
from studies.stimuli.sample import ROBOT, Sample
from studies.stimuli.trajectories import trajectory_sample
from studies.stimuli.write_settings import sets_delayed_strokes, write_settings


def load_robot_words(
    folder: str | Path, words: Sequence[str], delayed_strokes: bool = True
) -> dict[str, Sample]:
    """Robot samples from ``<folder>/<word>.json`` or ``<folder>/<word>/word.json``.

    With ``delayed_strokes`` False a word's marks (its dots and bars) are left out: the body
    alone, the paper's single stroke, whatever the file holds.

    Raises
    ------
    UsageError
        The folder or a word's file is missing or is not a word trajectory of that word.
    """
    from prg.pipeline.word import WordTrajectory

    folder = Path(folder)
    if not folder.is_dir():
        raise UsageError(f"--robot {folder}: no such folder of word trajectories")
    out = {}
    for word in words:
        candidates = [folder / f"{word}.json", folder / word / "word.json"]
        path = next((p for p in candidates if p.is_file()), None)
        if path is None:
            raise UsageError(
                f"--robot {folder}: no word trajectory for {word!r} ({word}.json or "
                f"{word}/word.json, as prg-write writes)"
            )
        traj = WordTrajectory.from_json(path)
        if traj.text != word:
            raise UsageError(f"{path}: holds {traj.text!r}, expected {word!r}")
        sample = trajectory_sample(traj, ROBOT, str(path))
        out[word] = sample if delayed_strokes else sample.without_delayed()
    return out


def unmarked_words(robot: dict[str, Sample]) -> list[str]:
    """Robot words with a letter that ``prg-write`` marks by default (dotted i/j, crossed t/f:
    :class:`prg.pipeline.marks.MarkSettings`) but no delayed stroke: words written with
    ``delayed_strokes=false`` (or by a version without marks)."""
    from prg.pipeline.marks import MarkSettings

    marks = MarkSettings()
    letters = set(marks.dotted + marks.crossed)
    return [w for w, s in robot.items() if not s.delayed and letters & set(w)]


def checkpoint(family: str, ckpt: str | Path | None) -> Path:
    """``ckpt``, or the exported model of ``family`` under the project root's ``models/`` (as
    ``prg-write`` finds it); one that does not exist is refused naming its absolute path."""
    from prg.commands.cli import describe_root, project_root

    if ckpt is not None:
        path = Path(ckpt).resolve()
        if not path.exists():
            raise UsageError(f"ckpt={path}: {path.absolute()} does not exist")
        return path
    root = project_root()[0]
    path = root / "models" / family / "model.ckpt"
    if not path.exists():
        raise UsageError(
            f"checkpoint {path.absolute()} does not exist: no {family} model under "
            f"models_dir ({describe_root(root)}); give ckpt=FILE, "
            "PRG_ROOT=FOLDER for another project, or train it there (`make demo`)"
        )
    return path


def generate_robot_words(
    words: Sequence[str],
    out_dir: str | Path,
    family: str = "muse",
    ckpt: str | Path | None = None,
    overrides: Sequence[str] = (),
    progress: Callable[[str], None] | None = None,
    delayed_strokes: bool = True,
    hand_per_word: bool = True,
    seed: int | None = None,
) -> dict[str, Path]:
    """Write each word with one :class:`prg.writer.Writer` (the model loaded once).

    Parameters
    ----------
    words : sequence of str
    out_dir : path
        Receives ``<word>.json`` (the word trajectories).
    family : str
        Model family; its checkpoint is ``models/<family>/model.ckpt`` unless ``ckpt`` is given.
    ckpt : path, optional
    overrides : sequence of str
        ``prg-write`` settings as its overrides (e.g. ``generate.temperature=0.3``), read by
        :func:`~studies.stimuli.write_settings.write_settings`; not ``delayed_strokes``, which
        is the argument below.
    progress : callable, optional
        Called with a line per word.
    delayed_strokes : bool
        ``prg-write``'s ``delayed_strokes``: True dots the i's and j's and crosses the t's and
        f's after the cursive word; False writes the paper's single stroke.
    hand_per_word : bool
        True (the study's ``robot.hands: per_word``): word ``i`` is written with
        ``generate.seed`` + ``i``, each in its own hand, as each trial's human words are by
        different people; False: every word with the one seed, in one hand.
    seed : int, optional
        ``generate.seed`` in place of the overrides' (the judge's further hands).

    Returns
    -------
    dict of str to Path

    Raises
    ------
    UsageError
        A bad override (one that sets ``delayed_strokes`` too), a missing checkpoint.
    """
    from prg.writer import Writer

    if not isinstance(delayed_strokes, bool):
        raise UsageError(f"delayed_strokes must be true or false, got {delayed_strokes!r}")
    clash = next((o for o in overrides if sets_delayed_strokes(o)), None)
    if clash is not None:
        raise UsageError(
            f"robot.write_overrides: {clash!r}: delayed_strokes is set by the study's "
            "top-level delayed_strokes"
        )
    settings = write_settings(overrides, delayed_strokes, family)
    base = settings.generate if seed is None else replace(settings.generate, seed=seed)
    path = checkpoint(family, ckpt)
    if settings.style is not None and not isinstance(settings.style, str):
        raise UsageError(f"style must be a file path, got {settings.style!r}")
    if settings.threads:
        import torch

        torch.set_num_threads(int(settings.threads))
    writer = Writer.from_checkpoint(
        path, settings=base, on_unknown=settings.on_unknown, style=settings.style
    )
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = {}
    for i, word in enumerate(words):
        if progress:
            progress(f"robot writes {word!r} ({i + 1}/{len(words)})")
        if hand_per_word:
            writer.settings = replace(base, seed=base.seed + i)
        paths[word] = writer.write(text=word).word.to_json(out_dir / f"{word}.json")
    return paths
