"""An automatic judge before the participants: do a study's stimuli give the robot away?

``prg-study judge FOLDER`` reads a built study (its ``stimuli.csv`` and the samples behind it)
and scores the robot's words against the human words of the same study:

- a **classifier two-sample test** (C2ST), on the trajectories (each word's pen-down strokes in
  writing order, normalised for position and height, 128 points by arc length, with the hand
  features of :func:`prg.evaluation.styles.writer_features`: stroke directions, turning angles,
  aspect, roughness, slant) and on the rendered stimulus images (the study's own PNGs, 24 x 96
  grey), every feature centred word by word (what tells the robot from the people, not one word
  from another): a standardised logistic
  regression with balanced class weights, cross-validated leaving one word out (so the word's
  shape does not tell), scored by balanced accuracy (0.5: indistinguishable), with a 95 %
  interval by bootstrapping the words;
- a **simulated observer** for the Turing study's question (pick the robot among one robot and
  ``n_options - 1`` humans; chance ``1 / n_options``, the paper's participants 0.42): for each
  word, trained on the other words' samples (the same classifier on both feature sets), it
  picks the option it finds most robot-like in ``trials_per_word`` random trials; its pick rate
  with a 95 % interval by bootstrapping the words.

On a pilot build the human words are held-out writers' letters from the dataset, joined the way
the robot's are (:func:`held_out_words`); on a real build, the recorded human words. The result
is written to ``judge.json`` in the folder and printed.
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from prg.errors import UsageError
from prg.evaluation.styles import writer_features

N_POINTS = 128
IMAGE_SHAPE = (24, 96)
ROBOT = "robot"


@dataclass(frozen=True)
class Stimulus:
    """One word of a built study: its writer, its strokes and its rendered image (a file, or
    an image drawn for the judge)."""

    word: str
    writer_id: str
    strokes: tuple[np.ndarray, ...]
    image: Path | object


def read_stimuli(folder: str | os.PathLike) -> list[Stimulus]:
    """The samples of a built study, from its ``stimuli.csv`` and the files it names.

    Raises
    ------
    UsageError
        If the folder is not a built study or a sample's file cannot be read.
    """
    from studies.stimuli import load_robot_words, read_json_sample, read_svg

    folder = Path(folder)
    table = folder / "stimuli.csv"
    if not table.is_file():
        raise UsageError(f"{folder}: not a built study (no stimuli.csv): run prg-study build first")
    with table.open(encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    if not rows:
        raise UsageError(f"{table}: no stimuli")
    words = sorted({r["word"] for r in rows})
    robot = load_robot_words(folder / "sources" / ROBOT, words)
    out = []
    for r in rows:
        if r["writer_id"] == ROBOT:
            sample = robot[r["word"]]
        else:
            origin = Path(r["origin"])
            origin = origin if origin.is_absolute() else folder / origin
            if not origin.is_file():
                raise UsageError(
                    f"{table}: the sample of {r['writer_id']!r} for {r['word']!r} names "
                    f"{r['origin']!r}, which is not a file (stand-ins from older pilot builds "
                    "have none: rebuild the pilot)"
                )
            found = (
                read_json_sample(origin, origin.parent.parent)
                if origin.suffix == ".json"
                else read_svg(origin, origin.parent.parent)
            )
            sample = next(s for s in found if s.word == r["word"] and s.writer_id == r["writer_id"])
        out.append(Stimulus(r["word"], r["writer_id"], sample.strokes, folder / r["file"]))
    return out


def trajectory_features(strokes: tuple[np.ndarray, ...]) -> np.ndarray:
    """The word's strokes in writing order as one path, centred, scaled to unit height, at
    :data:`N_POINTS` points equally spaced along it (x then y), shape (2 * N_POINTS,)."""
    path = np.concatenate([np.asarray(s, dtype=np.float64) for s in strokes])
    path = path - path.mean(0)
    path = path / max(float(np.ptp(path[:, 1])), 1e-9)
    steps = np.linalg.norm(np.diff(path, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(steps)])
    s = np.linspace(0.0, arc[-1], N_POINTS)
    return np.concatenate([np.interp(s, arc, path[:, 0]), np.interp(s, arc, path[:, 1])])


def image_features(image) -> np.ndarray:
    """The stimulus image (a PNG file or a PIL image), grey, :data:`IMAGE_SHAPE`, ink 1 and
    paper 0, flattened."""
    from PIL import Image

    im = Image.open(image) if isinstance(image, str | os.PathLike) else image
    grey = im.convert("L").resize(IMAGE_SHAPE[::-1], Image.Resampling.BOX)
    return 1.0 - np.asarray(grey, dtype=np.float64).ravel() / 255.0


def more_robot_words(folder: str | os.PathLike, per_word: int) -> list[Stimulus]:
    """``per_word`` more robot samples of each study word, written as the study's robot wrote
    (``manifest.json``'s ``robot``: family, checkpoint, overrides, one hand per word; a study
    whose robot words were given as files, ``robot.dir``, is refused) in other hands (``generate.seed`` moved on by the number of words each time) and
    drawn in the study's style: the study shows one robot word a word, which leaves the judge
    little to learn from."""
    import tempfile

    from prg.files import read_json
    from studies.stimuli import RenderStyle, generate_robot_words, load_robot_words, render_sample

    manifest = read_json(Path(folder) / "manifest.json", "the study's manifest.json")
    robot = manifest.get("robot")  # the robot settings the study was built with
    words = manifest.get("words")
    if not isinstance(robot, dict) or not isinstance(words, list) or not words:
        raise UsageError(
            f"{folder}: its manifest.json does not say how its robot wrote (built before the "
            "judge could write more robot words): rebuild the study"
        )
    if robot.get("dir"):
        raise UsageError(
            f"{folder}: its robot words were given as files ({robot['dir']}): the judge cannot "
            "write more of them; judge without --robot-words"
        )
    style = RenderStyle.from_dict(manifest["render"])
    delayed = bool(manifest.get("delayed_strokes", True))
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(1, per_word + 1):
            where = Path(tmp) / str(k)
            generate_robot_words(
                words,
                where,
                family=robot["family"],
                ckpt=robot.get("ckpt"),
                overrides=robot["write_overrides"],
                delayed_strokes=delayed,
                hand_per_word=robot.get("hands", "per_word") == "per_word",
                seed=k * len(words),
            )
            for word, sample in load_robot_words(where, words, delayed).items():
                image = render_sample(sample, style)
                out.append(Stimulus(word, ROBOT, sample.strokes, image))
    return out


def word_centred(x: np.ndarray, words: np.ndarray) -> np.ndarray:
    """``x`` with each word's rows centred on their mean."""
    out = np.asarray(x, dtype=np.float64).copy()
    for word in np.unique(words):
        out[words == word] -= out[words == word].mean(0)
    return out


def _classifier():
    from sklearn.linear_model import LogisticRegression
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    return make_pipeline(
        StandardScaler(), LogisticRegression(C=0.1, class_weight="balanced", max_iter=5000)
    )


def robot_scores(x: np.ndarray, is_robot: np.ndarray, words: np.ndarray) -> np.ndarray:
    """Each sample's probability of being the robot's, from a classifier trained on the other
    words' samples (leave one word out)."""
    scores = np.empty(len(x))
    for word in np.unique(words):
        held = words == word
        if is_robot[~held].all() or not is_robot[~held].any():
            raise UsageError("the judge needs robot and human samples of at least two words")
        model = _classifier().fit(x[~held], is_robot[~held])
        scores[held] = model.predict_proba(x[held])[:, 1]
    return scores


def _balanced_accuracy(scores, is_robot) -> float:
    picked = scores >= 0.5
    return 0.5 * (picked[is_robot].mean() + (~picked[~is_robot]).mean())


def _observer(scores, is_robot, words, n_humans, trials, rng) -> dict[str, float]:
    """Per word, the share of random trials (the robot and ``n_humans`` humans) in which the
    robot has the highest score."""
    rates = {}
    for word in np.unique(words):
        mine = np.flatnonzero(words == word)
        robots, humans = mine[is_robot[mine]], mine[~is_robot[mine]]
        if not len(robots) or len(humans) < n_humans:
            continue
        hits = 0
        for _ in range(trials):
            shown = rng.choice(humans, size=n_humans, replace=False)
            hits += scores[rng.choice(robots)] > scores[shown].max()
        rates[str(word)] = hits / trials
    return rates


def _bootstrap(values_by_word: dict[str, float], rng, n: int = 2000) -> tuple[float, float]:
    values = np.array(list(values_by_word.values()))
    means = rng.choice(values, size=(n, len(values)), replace=True).mean(1)
    return float(np.percentile(means, 2.5)), float(np.percentile(means, 97.5))


def judge(
    folder: str | os.PathLike,
    n_options: int = 5,
    trials_per_word: int = 200,
    seed: int = 0,
    robot_per_word: int = 0,
):
    """Score a built study's stimuli (module docstring); returns the result as a dict and
    writes it to ``<folder>/judge.json``. ``robot_per_word`` > 0 adds that many robot words a
    word (:func:`more_robot_words`) to the study's one."""
    from prg.files import write_json

    stimuli = read_stimuli(folder)
    if robot_per_word:
        stimuli += more_robot_words(folder, robot_per_word)
    words = np.array([s.word for s in stimuli])
    is_robot = np.array([s.writer_id == ROBOT for s in stimuli])
    if not is_robot.any():
        raise UsageError(f"{folder}: no robot samples")
    rng = np.random.default_rng(seed)
    paths = np.stack([trajectory_features(s.strokes) for s in stimuli])
    hand = writer_features(np.hstack([paths[:, :N_POINTS, None], paths[:, N_POINTS:, None]]))
    features = {
        # each word's samples centred on their mean (label-free): what differs between the
        # robot and the people, not between the words
        "trajectories": np.hstack([word_centred(paths, words), word_centred(hand, words)]),
        "images": word_centred(np.stack([image_features(s.image) for s in stimuli]), words),
    }
    features["both"] = np.hstack([features["trajectories"], features["images"]])
    result = {
        "folder": str(folder),
        "words": len(np.unique(words)),
        "robot_samples": int(is_robot.sum()),
        "human_samples": int((~is_robot).sum()),
        "n_options": n_options,
        "robot_per_word": 1 + robot_per_word,
        "chance": 1.0 / n_options,
        "paper_participants": 0.42,
        "c2st": {},
    }
    scores = {}
    for name, x in features.items():
        scores[name] = robot_scores(x, is_robot, words)
        by_word = {
            str(w): _balanced_accuracy(scores[name][words == w], is_robot[words == w])
            for w in np.unique(words)
        }
        low, high = _bootstrap(by_word, rng)
        result["c2st"][name] = {
            "balanced_accuracy": _balanced_accuracy(scores[name], is_robot),
            "ci95": [low, high],
        }
    rates = _observer(scores["both"], is_robot, words, n_options - 1, trials_per_word, rng)
    if not rates:
        raise UsageError(f"{folder}: no word has {n_options - 1} human samples for the observer")
    low, high = _bootstrap(rates, rng)
    result["observer"] = {
        "pick_rate": float(np.mean(list(rates.values()))),
        "ci95": [low, high],
        "by_word": rates,
        "trials_per_word": trials_per_word,
    }
    write_json(Path(folder) / "judge.json", result)
    return result


def summary_lines(result: dict) -> list[str]:
    """What ``prg-study judge`` prints."""
    obs = result["observer"]
    lines = [
        f"{result['words']} words, {result['robot_samples']} robot and "
        f"{result['human_samples']} human samples",
    ]
    for name, c in result["c2st"].items():
        lines.append(
            f"C2ST on {name}: balanced accuracy {c['balanced_accuracy']:.2f} (95 % CI "
            f"{c['ci95'][0]:.2f}-{c['ci95'][1]:.2f}; 0.5: indistinguishable)"
        )
    lines.append(
        f"simulated observer picks the robot among {result['n_options']}: {obs['pick_rate']:.2f} "
        f"(95 % CI {obs['ci95'][0]:.2f}-{obs['ci95'][1]:.2f}; chance {result['chance']:.2f}, "
        f"the paper's participants {result['paper_participants']:.2f})"
    )
    return lines
