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

import dataclasses
import os
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from prg.alphabet import NUM_CLASSES, label_to_char, text_to_labels, unsupported_chars
from prg.data.hands import HandBank
from prg.errors import UsageError
from prg.files import read_json
from prg.models.base import MultimodalVAE
from prg.models.modalities import LABEL, TRAJ
from prg.pipeline.perceive import perceive_trajectories

#: How strongly a style's linear map is pulled to the identity (a share of the letters' own
#: spread): one letter gives a noisy map. On the demo MUSE, the writer-identification rate of
#: letters written in held-out writers' styles (``reports/styles.md``) was, for k = 1 / 5 / 15
#: letters: 0.30 / 0.38 / 0.39 with the nearest writer and no map, 0.36 / 0.44 / 0.46 with a
#: map pulled by 0.1, 0.37 / 0.49 / 0.45 with 0.03 and the writer chosen after alignment.
STYLE_RIDGE = 0.03
#: How many of the nearest bank writers a person's style blends: each letter's code is the
#: mean of those writers' codes for it (and the map the mean of their maps). A held-out writer
#: is a new hand, between the bank's: on the demo MUSE, the writer-identification ratio
#: (generated over real, 5 seeds) for k = 1 / 5 / 15 letters was 0.72 / 0.74 / 0.80 with the
#: nearest writer alone and 0.69 / 0.81 / 0.87 with the 5 nearest, on the validation split's
#: writers (where the number was chosen; 3 and 8 writers: 0.84 and 0.85 at k = 15).
STYLE_WRITERS = 5


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
    transform : ndarray, shape (2, 2), optional
        The linear map (slant, width, rotation) from the writer's letters to the person's,
        applied to the letters written from the writer's (:func:`fit_transform`).
    blend : tuple of int, optional
        Bank writers whose letters' codes are averaged for the classes not given (``writer``
        first; empty: ``writer`` alone).
    """

    writer: int
    own_traj: np.ndarray | None = None
    own_label: np.ndarray | None = None
    transform: np.ndarray | None = None
    blend: tuple[int, ...] = ()


def random_hand(bank: HandBank, seed: int) -> Hand:
    """The hand of seed ``seed``: the bank's writers in one fixed shuffled order, seed ``s``
    the ``s``-th (modulo their number), so seeds 0 .. n-1 are n different writers, as n
    people are."""
    order = np.random.default_rng(len(bank.writers)).permutation(len(bank.writers))
    return Hand(int(order[seed % len(bank.writers)]))


def fit_transform(own: np.ndarray, reference: np.ndarray, ridge: float = STYLE_RIDGE) -> np.ndarray:
    """The 2 x 2 map A with ``own`` ~ ``reference`` A^T, letter by letter centred, by least
    squares pulled to the identity: min sum ||x - A y||^2 + ridge * n * ||A - I||^2.

    Parameters
    ----------
    own, reference : ndarray, shape (k, 200)
        Letters in pairs of one class (normalised, interleaved x, y).

    Returns
    -------
    ndarray, shape (2, 2)

    Examples
    --------
    >>> y = np.random.default_rng(0).normal(size=(3, 200))
    >>> shear = np.array([[1.0, 0.3], [0.0, 1.0]])
    >>> x = (y.reshape(3, 100, 2) @ shear.T).reshape(3, 200)
    >>> np.round(fit_transform(x, y, ridge=0.0), 6)
    array([[1. , 0.3],
           [0. , 1. ]])
    """

    def centred(letters):
        xy = np.asarray(letters, dtype=np.float64).reshape(len(letters), -1, 2)
        return (xy - xy.mean(1, keepdims=True)).reshape(-1, 2)

    x, y = centred(own), centred(reference)
    pull = ridge * len(x) * np.eye(2)
    return np.linalg.solve(y.T @ y + pull, y.T @ x + pull).T


def apply_transform(letters: np.ndarray, transform: np.ndarray) -> np.ndarray:
    """Each letter (N, 100, 2) mapped by ``transform`` and normalised again as the dataset's
    (centred, largest absolute coordinate 1)."""
    mapped = np.asarray(letters, dtype=np.float64) @ np.asarray(transform).T
    mapped = mapped - mapped.mean(1, keepdims=True)
    return mapped / np.abs(mapped).max((1, 2), keepdims=True)


def hand_distances(
    bank: HandBank, traj: np.ndarray, labels: np.ndarray, ridge: float = STYLE_RIDGE
) -> tuple[np.ndarray, np.ndarray]:
    """How far each bank writer's hand is from a person's letters, once aligned.

    For each writer, each given letter is paired with the writer's nearest letter of its
    class; the pairs give the writer's map (:func:`fit_transform`), and the distance is the
    mean distance from the person's letters to the mapped ones. A writer with fewer than half
    of the given classes is ``inf``: never chosen.

    Parameters
    ----------
    traj : ndarray, shape (k, 200)
    labels : ndarray, shape (k,)

    Returns
    -------
    distances : ndarray, shape (len(bank.writers),)
    transforms : ndarray, shape (len(bank.writers), 2, 2)
    """
    traj = np.asarray(traj, dtype=np.float64)
    labels = np.asarray(labels)
    distances = np.full(len(bank.writers), np.inf)
    transforms = np.tile(np.eye(2), (len(bank.writers), 1, 1))
    for w in range(len(bank.writers)):
        pairs, refs = [], []
        for i, y in enumerate(labels):
            theirs = np.flatnonzero((bank.writer == w) & (bank.label == y))
            if len(theirs):
                nearest = theirs[np.argmin(np.linalg.norm(bank.traj[theirs] - traj[i], axis=1))]
                pairs.append(i)
                refs.append(bank.traj[nearest])
        if not pairs or len(pairs) < len(labels) / 2:
            continue
        transforms[w] = fit_transform(traj[pairs], np.array(refs), ridge)
        mapped = apply_transform(np.array(refs).reshape(len(refs), -1, 2), transforms[w])
        distances[w] = np.linalg.norm(mapped.reshape(len(refs), -1) - traj[pairs], axis=1).mean()
    return distances, transforms


def match_hand(bank: HandBank, traj: np.ndarray, labels: np.ndarray) -> Hand:
    """The hand of a person who wrote ``traj`` (classes ``labels``): their own letters, and for
    the rest a blend of the :data:`STYLE_WRITERS` bank writers whose letters of the same classes
    are nearest theirs once aligned (:func:`hand_distances`), with the mean of their maps.

    Raises
    ------
    UsageError
        If no bank writer has at least half of the given classes.
    """
    distances, transforms = hand_distances(bank, traj, labels)
    if not np.isfinite(distances).any():
        given = "".join(label_to_char(int(y)) for y in labels)
        raise UsageError(f"style letters {given!r}: the model's writers wrote too few of them")
    nearest = np.argsort(distances, kind="stable")[:STYLE_WRITERS]
    nearest = nearest[np.isfinite(distances[nearest])]
    return Hand(
        int(nearest[0]),
        np.asarray(traj, dtype=np.float32),
        np.asarray(labels, dtype=np.int64),
        transforms[nearest].mean(0),
        tuple(int(w) for w in nearest),
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
                fallback = hand_distances(bank, bank.traj[mine], bank.label[mine])[0]
                fallback[hand.writer] = np.inf
            writers = np.unique(bank.writer[same])
            nearest = writers[np.argmin(fallback[writers])]
            theirs = same[bank.writer[same] == nearest]
        out[i] = bank.traj[rng.choice(theirs)]
    return out


def component_inputs(model: MultimodalVAE, traj: np.ndarray, labels: np.ndarray) -> dict:
    """The model inputs a component letter is encoded from: its trajectory and label where the
    family takes both (MUSE's joint posterior, the CVAE's encoder, the MVAE's product), its
    trajectory alone otherwise (an AVAE's trajectory expert, the MMVAE's and MoPoE's trajectory
    component: their posterior from both is a mixture, not one code)."""
    accepted = {frozenset(s) for s in model.accepted_inputs}
    traj_input = torch.from_numpy(np.asarray(traj, dtype=np.float32))
    # a mixture family (MMVAE, MoPoE) mixes T and S into two modes: its trajectory's own posterior
    if frozenset((TRAJ, LABEL)) in accepted and not model.mixture_posterior:
        return {TRAJ: traj_input, LABEL: torch.as_tensor(np.asarray(labels), dtype=torch.long)}
    if frozenset((TRAJ,)) in accepted:
        return {TRAJ: traj_input}
    raise UsageError(f"{model.family} cannot encode a letter's trajectory: no hands to write in")


@torch.no_grad()
def decoder_bias(model: MultimodalVAE, bank: HandBank) -> np.ndarray:
    """Per class, the mean of (letter - its reconstruction) over the bank's letters: what the
    decoder systematically misses of a class (a too-round loop, a short tail), added back to
    every letter decoded in a hand.

    A linear classifier tells the demo MUSE's decoded letters from held-out writers' by this
    bias (C2ST 0.68); with it added back, 0.57, as real letters of other writers (0.59). It is
    a property of the decoder, estimated on the training originals: no letter is copied.

    Returns
    -------
    ndarray, shape (NUM_CLASSES, 200), float32
        Zero rows for classes the bank lacks.
    """
    decoded = decode_in_hand(model, bank.traj, bank.label, 0.0, seed=0)
    residual = bank.traj - decoded.reshape(len(bank), -1)
    out = np.zeros((NUM_CLASSES, bank.traj.shape[1]), dtype=np.float32)
    for c in np.unique(bank.label):
        out[c] = residual[bank.label == c].mean(0)
    return out


@torch.no_grad()
def decode_in_hand(
    model: MultimodalVAE,
    component: np.ndarray,
    labels: np.ndarray,
    temperature: float,
    seed: int,
    bias: np.ndarray | None = None,
) -> np.ndarray:
    """Sample each component letter's posterior (std scaled by ``temperature``) and decode it.

    The posterior is the one in which the family reconstructs a trajectory: a family with a
    VAE per modality (MUSE, the AVAEs) uses its trajectory VAE, q(z_T | x_T) and g_T; the CVAE
    its encoder and decoder given the label. MUSE's top level (8 dims, shared with the label
    and the image) keeps a letter's class but blurs its hand: on the demo model, letters drawn
    through it reached recall 0.45 and C2ST 0.81 against held-out writers, through the
    trajectory VAE 0.9 and 0.6 (``reports/likeness.md``).

    Parameters
    ----------
    component : ndarray, shape (N, 200) or (M, N, 200)
        One real letter per letter (:func:`components`), or M of them per letter whose codes
        (posterior means and log-variances) are averaged (a blend of M writers).
    labels : ndarray, shape (N,)
    bias : ndarray, shape (NUM_CLASSES, 200), optional
        Added to each decoded letter by its class (:func:`decoder_bias`).

    Returns
    -------
    ndarray, shape (N, 100, 2)
        Normalised letter trajectories (y up).
    """
    blended = np.asarray(component, dtype=np.float32)
    blended = blended[None] if blended.ndim == 2 else blended
    own = getattr(model, "encoders", None)
    if own is not None and TRAJ in own:
        codes = [own[TRAJ](torch.from_numpy(c)) for c in blended]
        decode = model.decoders[TRAJ]
    else:
        codes = [model.encode(component_inputs(model, c, labels)) for c in blended]
        codes = [(q.mu, q.logvar) for q in codes]
        context = {LABEL: torch.as_tensor(np.asarray(labels), dtype=torch.long)}

        def decode(z):
            return model.decode(z, TRAJ, context)

    mu = torch.stack([m for m, _ in codes]).mean(0)
    logvar = torch.stack([v for _, v in codes]).mean(0)

    generator = torch.Generator().manual_seed(int(seed))
    eps = torch.randn(mu.shape, generator=generator) * float(temperature)
    out = model.likelihoods.mean(TRAJ, decode(mu + eps * (0.5 * logvar).exp())).numpy()
    out = out.astype(np.float64)
    if bias is not None:
        out = out + bias[np.asarray(labels)]
    return out.reshape(len(out), -1, 2)


def write_in_hand(
    model: MultimodalVAE,
    bank: HandBank,
    hand: Hand,
    labels: np.ndarray,
    temperature: float,
    seed: int,
    bias: np.ndarray | None = None,
) -> np.ndarray:
    """The letters ``labels`` in ``hand``: :func:`components` (of each writer of the hand's
    blend), :func:`decode_in_hand`, and the hand's map (:attr:`Hand.transform`) on the letters
    written from the bank writers'.

    Returns
    -------
    ndarray, shape (N, 100, 2)
    """
    labels = np.asarray(labels)
    blend = [
        components(bank, dataclasses.replace(hand, writer=w), labels, seed)
        for w in (hand.blend or (hand.writer,))
    ]
    letters = decode_in_hand(model, np.stack(blend), labels, temperature, seed, bias)
    if hand.transform is not None:
        own = hand.own_label if hand.own_label is not None else np.zeros(0, dtype=np.int64)
        theirs = ~np.isin(labels, own)
        letters[theirs] = apply_transform(letters[theirs], hand.transform)
    return letters


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
    command = model.encode(inputs).mean  # a mixture posterior's: the mean of its components
    out = np.empty((len(labels), bank.traj.shape[1]), dtype=np.float32)
    for y in np.unique(labels):
        same = np.flatnonzero(bank.label == y)
        if not len(same):
            raise UsageError(
                f"letter {label_to_char(int(y))!r}: the model's writers never wrote it"
            )
        codes = model.encode(component_inputs(model, bank.traj[same], bank.label[same])).mean
        rows = np.flatnonzero(labels == y)
        nearest = torch.cdist(command[rows], codes).argmin(-1).numpy()
        out[rows] = bank.traj[same[nearest]]
    return out
