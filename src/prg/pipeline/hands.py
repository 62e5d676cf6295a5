"""Writers' hands: letters drawn from the posteriors of real writers' letters, one hand a word.

Decoding a letter's posterior mean from its label (the paper) gives every ``a`` the same ``a``,
the blend of all styles; sampling the label's posterior gives variety but leaves the letter (the
label's posterior is broad, and much of it decodes to no letter). Here a letter is drawn from
the *aggregate posterior* of the real letters of its class, q(z | y) = 1/N sum_i q(z | x_i, y),
as a mixture over the original (not augmented) training letters x_i: pick one real letter,
sample its posterior with the std scaled by ``temperature``, decode. Every sample then lies where
some real letter's code lies, and the set of them is spread as the writers' letters are.

A word is written in **one hand**: every letter's component is one writer's letter of that
class, so the letters agree in slant, width and roundness as one person's do. The writer is
chosen by the seed (:func:`random_hand`), or matched to a few letters a person gives
(:func:`match_hand`); classes the person gave are written from their own letters, the rest from
the nearest writer's. The training letters come with the checkpoint (:class:`HandBank`,
``checkpoint["hands"]``): only the originals, since the sigma-lognormal augmentation moves
letters off the writers' manifold (precision 0.67 against 0.92 for real letters, issue notes).
"""

from __future__ import annotations

import os
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from prg.alphabet import label_to_char, text_to_labels, unsupported_chars
from prg.data.hands import HandBank
from prg.errors import UsageError
from prg.files import read_json
from prg.models.base import MultimodalVAE
from prg.models.modalities import LABEL, TRAJ
from prg.pipeline.perceive import perceive_trajectories


@dataclass(frozen=True)
class Hand:
    """The hand a word is written in: a bank writer, and a person's own letters if given.

    Attributes
    ----------
    writer : int
        Index of the bank writer whose letters are the components for the classes not given.
    own_traj : ndarray, shape (k, 200), optional
        A person's letters (normalised), the components for their classes.
    own_label : ndarray, shape (k,), optional
    """

    writer: int
    own_traj: np.ndarray | None = None
    own_label: np.ndarray | None = None


def random_hand(bank: HandBank, seed: int) -> Hand:
    """The hand of seed ``seed``: the bank's writers in one fixed shuffled order, seed ``s``
    the ``s``-th (modulo their number), so seeds 0 .. n-1 are n different writers, as n
    people are."""
    order = np.random.default_rng(len(bank.writers)).permutation(len(bank.writers))
    return Hand(int(order[seed % len(bank.writers)]))


def hand_distances(bank: HandBank, traj: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Mean distance from a person's letters to each bank writer's nearest letter of the same
    class; ``inf`` for a writer with none of those classes.

    Parameters
    ----------
    traj : ndarray, shape (k, 200)
    labels : ndarray, shape (k,)

    Returns
    -------
    ndarray, shape (len(bank.writers),)
    """
    total = np.zeros(len(bank.writers))
    count = np.zeros(len(bank.writers))
    for x, y in zip(np.asarray(traj, dtype=np.float64), np.asarray(labels), strict=True):
        same = np.flatnonzero(bank.label == y)
        if not len(same):
            continue
        d = np.linalg.norm(bank.traj[same] - x, axis=1)
        nearest = np.full(len(bank.writers), np.inf)
        np.minimum.at(nearest, bank.writer[same], d)
        seen = np.isfinite(nearest)
        total[seen] += nearest[seen]
        count[seen] += 1
    with np.errstate(invalid="ignore", divide="ignore"):
        # a writer is compared on the letters they have; one without any is never chosen
        return np.where(count > 0, total / np.maximum(count, 1), np.inf)


def match_hand(bank: HandBank, traj: np.ndarray, labels: np.ndarray) -> Hand:
    """The hand of a person who wrote ``traj`` (classes ``labels``): their own letters, and the
    bank writer whose letters of the same classes are nearest theirs for the rest.

    Raises
    ------
    UsageError
        If no bank writer has any of the given classes.
    """
    distances = hand_distances(bank, traj, labels)
    if not np.isfinite(distances).any():
        given = "".join(label_to_char(int(y)) for y in labels)
        raise UsageError(f"style letters {given!r}: the model's writers wrote none of them")
    return Hand(
        int(np.argmin(distances)),
        np.asarray(traj, dtype=np.float32),
        np.asarray(labels, dtype=np.int64),
    )


def components(bank: HandBank, hand: Hand, labels: np.ndarray, seed: int) -> np.ndarray:
    """One real letter per letter to write, in ``hand``: the person's own letter of that class
    if they gave one, else the hand's writer's, else (a class that writer never wrote) the
    nearest writer's who did, nearest by :func:`hand_distances` on the hand's writer's letters.

    Returns
    -------
    ndarray, shape (N, 200), float32
    """
    rng = np.random.default_rng(seed)
    out = np.empty((len(labels), bank.traj.shape[1]), dtype=np.float32)
    fallback: np.ndarray | None = None
    for i, y in enumerate(np.asarray(labels)):
        own = np.flatnonzero(hand.own_label == y) if hand.own_label is not None else []
        if len(own):
            out[i] = hand.own_traj[rng.choice(own)]
            continue
        same = np.flatnonzero(bank.label == y)
        if not len(same):
            raise UsageError(
                f"letter {label_to_char(int(y))!r}: the model's writers never wrote it"
            )
        theirs = same[bank.writer[same] == hand.writer]
        if not len(theirs):
            if fallback is None:
                mine = bank.writer == hand.writer
                fallback = hand_distances(bank, bank.traj[mine], bank.label[mine])
                fallback[hand.writer] = np.inf
            writers = np.unique(bank.writer[same])
            nearest = writers[np.argmin(fallback[writers])]
            theirs = same[bank.writer[same] == nearest]
        out[i] = bank.traj[rng.choice(theirs)]
    return out


def component_inputs(model: MultimodalVAE, traj: np.ndarray, labels: np.ndarray) -> dict:
    """The model inputs a component letter is encoded from: its trajectory and label where the
    family takes both (MUSE's joint posterior, the CVAE's encoder), its trajectory alone
    otherwise (an AVAE's trajectory expert)."""
    accepted = {frozenset(s) for s in model.accepted_inputs}
    traj_input = torch.from_numpy(np.asarray(traj, dtype=np.float32))
    if frozenset((TRAJ, LABEL)) in accepted:
        return {TRAJ: traj_input, LABEL: torch.as_tensor(np.asarray(labels), dtype=torch.long)}
    if frozenset((TRAJ,)) in accepted:
        return {TRAJ: traj_input}
    raise UsageError(f"{model.family} cannot encode a letter's trajectory: no hands to write in")


@torch.no_grad()
def decode_in_hand(
    model: MultimodalVAE, component: np.ndarray, labels: np.ndarray, temperature: float, seed: int
) -> np.ndarray:
    """Sample each component letter's posterior (std scaled by ``temperature``) and decode it.

    Parameters
    ----------
    component : ndarray, shape (N, 200)
        One real letter per letter (:func:`components`).
    labels : ndarray, shape (N,)

    Returns
    -------
    ndarray, shape (N, 100, 2)
        Normalised letter trajectories (y up).
    """
    inputs = component_inputs(model, component, labels)
    posterior = model.encode(inputs)
    generator = torch.Generator().manual_seed(int(seed))
    eps = torch.randn(posterior.mu.shape, generator=generator) * float(temperature)
    z = posterior.mu + eps * (0.5 * posterior.logvar).exp()
    context = {LABEL: torch.as_tensor(np.asarray(labels), dtype=torch.long)}
    out = model.likelihoods.mean(TRAJ, model.decode(z, TRAJ, context))
    return out.numpy().reshape(len(out), -1, 2).astype(np.float64)


#: Style files :func:`read_style` reads, for messages.
STYLE_FORMATS = (
    "a capture-page recording (.json, one letter per sample), a UJI-format file (.txt) or an "
    ".npz with traj (k, 200) and text (k letters)"
)


def read_style(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """A person's letters from a style file: normalised trajectories and their classes.

    Accepted (:data:`STYLE_FORMATS`):

    - a capture-page recording (schema ``prg.handwriting_capture``): the samples whose word is
      one supported character, written in one stroke (others are skipped);
    - a UJI Pen Characters file: its single-stroke samples of 0-9, A-Z, a-z;
    - an ``.npz`` (read without pickles) with ``traj`` (k, 200), normalised as the dataset, and
      ``text``, a string of the k letters.

    Returns
    -------
    traj : ndarray, shape (k, 200), float32
    labels : ndarray, shape (k,), int64

    Raises
    ------
    UsageError
        Naming the file: unreadable, not one of the formats, or no usable letter in it.
    """
    path = Path(path)
    if not path.is_file():
        raise UsageError(f"style {path}: no such file; give {STYLE_FORMATS}")
    suffix = path.suffix.lower()
    if suffix == ".npz":
        traj, text = _read_style_npz(path)
    elif suffix == ".json":
        strokes, text = _read_style_capture(path)
        traj = perceive_trajectories(strokes, y_down=True) if strokes else np.zeros((0, 200))
    else:
        strokes, text = _read_style_uji(path)
        traj = perceive_trajectories(strokes, y_down=True) if strokes else np.zeros((0, 200))
    if not len(text):
        raise UsageError(f"style {path}: no single-stroke letter of 0-9, A-Z, a-z in it")
    return np.asarray(traj, dtype=np.float32), np.asarray(text_to_labels(text), dtype=np.int64)


def _read_style_npz(path: Path) -> tuple[np.ndarray, str]:
    try:
        with np.load(path, allow_pickle=False) as npz:
            traj, text = npz["traj"], str(npz["text"])
    except (OSError, ValueError, KeyError, zipfile.BadZipFile) as err:
        raise UsageError(
            f"style {path}: not an .npz with traj (k, 200) and text ({type(err).__name__})"
        ) from None
    if traj.ndim != 2 or traj.shape[1] != 200 or len(traj) != len(text):
        raise UsageError(
            f"style {path}: traj has shape {traj.shape} for {len(text)} letters in text; "
            "accepted is (k, 200) with k the letters of text"
        )
    if not np.isfinite(traj).all():
        raise UsageError(f"style {path}: traj holds NaN or infinite values")
    text_to_labels(text)  # one clear error for characters outside 0-9, A-Z, a-z
    return traj, text


def _read_style_capture(path: Path) -> tuple[list[np.ndarray], str]:
    doc = read_json(path, "style file")
    if not isinstance(doc, dict) or doc.get("schema") != "prg.handwriting_capture":
        raise UsageError(f"style {path}: not a capture-page recording; give {STYLE_FORMATS}")
    samples = doc.get("samples")
    if not isinstance(samples, list):
        raise UsageError(f"style {path}: samples must be a list")
    strokes, text = [], ""
    for entry in samples:
        if not isinstance(entry, dict):
            continue
        word, raw = entry.get("word"), entry.get("strokes")
        if not isinstance(word, str) or len(word) != 1 or unsupported_chars(word):
            continue
        if not isinstance(raw, list) or len(raw) != 1 or not isinstance(raw[0], list):
            continue  # skipped, or written with a pen lift
        try:
            points = np.asarray([p[:2] for p in raw[0]], dtype=np.float64)
        except (TypeError, ValueError, IndexError):
            raise UsageError(
                f"style {path}: the stroke of {word!r} must hold [x, y] numbers"
            ) from None
        if points.ndim == 2 and len(points) >= 2:
            strokes.append(points)
            text += word
    return strokes, text


def _read_style_uji(path: Path) -> tuple[list[np.ndarray], str]:
    from prg.data.uji import read_uji

    samples = [s for s in read_uji(path) if len(s.strokes) == 1 and not unsupported_chars(s.char)]
    return [s.strokes[0] for s in samples], "".join(s.char for s in samples)


@torch.no_grad()
def nearest_components(
    model: MultimodalVAE, bank: HandBank, inputs: dict[str, torch.Tensor], labels: np.ndarray
) -> np.ndarray:
    """For a command given as images or trajectories: per letter, the bank letter of its class
    whose posterior mean is nearest the command's (in the model's latent space), so the written
    letter keeps the shape it was shown in, as a real writer's letter.

    Parameters
    ----------
    inputs : dict
        Per-letter model inputs the family accepts (N rows each).
    labels : ndarray, shape (N,)

    Returns
    -------
    ndarray, shape (N, 200), float32
    """
    command = model.encode(inputs).mu
    out = np.empty((len(labels), bank.traj.shape[1]), dtype=np.float32)
    for y in np.unique(labels):
        same = np.flatnonzero(bank.label == y)
        if not len(same):
            raise UsageError(
                f"letter {label_to_char(int(y))!r}: the model's writers never wrote it"
            )
        codes = model.encode(component_inputs(model, bank.traj[same], bank.label[same])).mu
        rows = np.flatnonzero(labels == y)
        nearest = torch.cdist(command[rows], codes).argmin(-1).numpy()
        out[rows] = bank.traj[same[nearest]]
    return out
