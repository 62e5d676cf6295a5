"""Human words for piloting a study before its human writers have written: held-out writers'
letters joined as the robot's are, or stand-ins made from the robot's own word."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from prg.errors import UsageError
from studies.stimuli.sample import Sample
from studies.stimuli.trajectories import trajectory_sample


def letter_samples(
    labels: np.ndarray, writers: np.ndarray, writer: str, wanted: Sequence[int], rng
) -> np.ndarray:
    """Row indices of ``writer``'s letters for the classes ``wanted``, one per letter, each drawn
    anew among the writer's samples of its class (the dataset holds two per class, as UJI's two
    sessions): a person does not write a letter the same way twice, so neither the two l's of
    "bell" nor the e's of two words are one copied sample wherever the writer wrote two."""
    return np.array(
        [rng.choice(np.flatnonzero((writers == writer) & (labels == y))) for y in wanted],
        dtype=np.int64,
    )


def held_out_words(
    words: Sequence[str],
    n: int,
    data_dir: str | Path,
    out_dir: str | Path,
    seed: int = 0,
    delayed_strokes: bool = True,
) -> dict[str, list[Sample]]:
    """Human words for a pilot: ``n`` writers of the dataset's test and validation splits
    (people no model was trained on) per word, each word made of that writer's own letters
    (:func:`letter_samples`), laid out and joined the way the
    robot's are (:func:`prg.pipeline.compose.compose_word` with ``prg-write``'s settings), so
    that what tells them apart is the letters and the hand, not the joining. Writers who did
    not write every letter of a word are skipped for it. Each word is saved as
    ``<out_dir>/<writer>/<word>.json`` (its sample's origin).

    Raises
    ------
    UsageError
        If the splits cannot be read, or fewer than ``n`` writers wrote a word's letters.
    """
    from dataclasses import replace

    from prg.alphabet import char_to_label
    from prg.data.store import load_split
    from prg.pipeline.compose import GenerateSettings, compose_word

    splits = [load_split(Path(data_dir) / f"{name}.npz") for name in ("test", "val")]
    keep = [~split["augmented"] for split in splits]
    traj = np.concatenate([sp["traj"][k] for sp, k in zip(splits, keep, strict=True)])
    traj = traj.reshape(len(traj), -1, 2)
    labels = np.concatenate([sp["label"][k] for sp, k in zip(splits, keep, strict=True)])
    writers = np.concatenate(
        [sp["writer"][k].astype(str) for sp, k in zip(splits, keep, strict=True)]
    )
    names = sorted(set(writers))
    rng = np.random.default_rng([seed, 11])  # the writers
    letter_rng = np.random.default_rng([seed, 12])  # their letters: the writers do not hang on it
    out: dict[str, list[Sample]] = {}
    for word in words:
        wanted = [char_to_label(c) for c in word if c != " "]
        able = [w for w in names if all(((writers == w) & (labels == y)).any() for y in wanted)]
        if len(able) < n:
            raise UsageError(
                f"pilot: only {len(able)} held-out writers wrote every letter of {word!r}; "
                f"{n} are needed"
            )
        out[word] = []
        for k, writer in enumerate(rng.choice(able, size=n, replace=False)):
            letters = traj[letter_samples(labels, writers, writer, wanted, letter_rng)]
            settings = replace(GenerateSettings(seed=k), delayed_strokes=delayed_strokes)
            traj_word, _ = compose_word(letters, word, settings)
            writer_id = f"pilot-{writer}"
            path = Path(out_dir) / writer_id / f"{word}.json"
            path.parent.mkdir(parents=True, exist_ok=True)
            traj_word.to_json(path)
            out[word].append(trajectory_sample(traj_word, writer_id, str(path)))
    return out


def stand_ins(
    robot: Sample, n: int, seed: int, amount: float = 0.08, delayed_strokes: bool = True
) -> list[Sample]:
    """``n`` placeholder "human" samples of the robot's word, for piloting a study before the
    human writers have written: the robot's strokes under a random shear/scale and a slow
    wobble, writers ``pilot01``, ``pilot02`` ... (``lifted`` False; never for real data).

    The robot's delayed strokes (its dots and bars, ``robot.delayed``) are kept as the stand-ins'
    delayed strokes, each moved with the part of the word nearest to it and keeping its own
    shape (a dot stays a dot); with ``delayed_strokes`` False they are left out.
    """
    if not delayed_strokes:
        robot = robot.without_delayed()
    pts = np.concatenate(robot.strokes)
    height = float(np.ptp(pts[:, 1])) or 1.0
    writing = [i for i in range(len(robot.strokes)) if i not in robot.delayed]
    anchors = np.concatenate([robot.strokes[i] for i in writing])
    out = []
    for k in range(n):
        rng = np.random.default_rng([seed, 5, k])
        a = np.eye(2) + rng.normal(0, amount, (2, 2))
        strokes: list[np.ndarray] = list(robot.strokes)
        shifts = []
        for i in writing:
            stroke = robot.strokes[i]
            u = np.linspace(0, 1, len(stroke))[:, None]
            wobble = np.sin(2 * np.pi * u * rng.uniform(1, 3, 2) + rng.uniform(0, 6, 2))
            strokes[i] = stroke @ a.T + wobble * amount * height * 0.5
            shifts.append(wobble * amount * height * 0.5)
        shift = np.concatenate(shifts)
        for i in robot.delayed:
            centre = robot.strokes[i].mean(axis=0)
            near = int(np.argmin(np.hypot(*(anchors - centre).T)))
            strokes[i] = robot.strokes[i] @ a.T + shift[near]
        out.append(
            Sample(
                robot.word,
                f"pilot{k + 1:02d}",
                tuple(strokes),
                "pilot stand-in",
                delayed=robot.delayed,
            )
        )
    return out
