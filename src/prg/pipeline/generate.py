"""Generate: per-letter latent -> trajectory -> laid-out word -> connection strokes -> one DMP.

:func:`decode_letters` runs the model's generation map psi'_T on per-letter inputs (any subset of
modalities the family accepts; extra modalities a family cannot use are dropped and reported).
:func:`write_word` then applies the final processing map (``prg.pipeline.layout``: sizes and
baseline; ``prg.pipeline.connect``: connection strokes) and fits one DMP to the whole word
(``prg.pipeline.dmp``).

Timing: a DMP starts and ends at rest, so the word is not fitted at constant pen speed (its
first samples would need an initial velocity the DMP does not have: an error of about 3 % of the
path length near the start). :func:`rest_to_rest_samples` resamples the path uniformly in time
under a speed profile that rises and falls with half-cosine ramps of ``ramp_s`` seconds and is
constant in between; the mean speed over the word stays ``speed_cm_s``.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np
import torch

from prg.checks import check_text_length
from prg.data.alphabet import char_to_label, label_to_char, text_to_labels, unsupported_chars
from prg.errors import UsageError
from prg.models.base import MODALITIES, MultimodalVAE
from prg.pipeline.connect import ConnectionParams, connect_sequence
from prg.pipeline.dmp import basis_count, fit_dmp, rollout
from prg.pipeline.layout import LayoutParams, layout_letters, word_breaks
from prg.pipeline.word import DEFAULT_SPEED_CM_S, WordTrajectory, assemble_word

log = logging.getLogger(__name__)

MAX_DMP_SAMPLES = 20_000  # 200 s of writing at 100 samples/s: about 1 GB and 25 s to fit


@dataclass(frozen=True)
class GenerateParams:
    """How a word is generated and timed (all config values, ``conf/write.yaml``).

    temperature : 0 decodes each letter's posterior mean; > 0 draws latents with their std
        scaled by it (variety), reproducibly for ``seed``.
    impute_steps : rounds of imputing the modalities a letter was not given before decoding
        (:meth:`prg.models.muse.MUSE.encode_imputed`; families without a joint posterior ignore
        it). 0 is the paper's decoding. The demo MUSE's letters from labels read right (folded
        coherence, whole test split) 0.68 with 0 rounds, 0.89 with 10, 0.94 with 20.
    method : ``"alg1"`` (the paper's connection algorithm) or ``"straight"``.
    speed_cm_s : mean pen speed over the word; ``ramp_s`` : start/stop ramp duration.
    samples_per_s : DMP demonstration samples per second of writing.
    basis_per_100_samples : DMP basis functions per 100 demonstration samples. Words from the
        decoder carry more detail than smooth test curves (corners where letters join): with
        70 per 100 samples at 100 samples/s, 30 random words of 6-12 letters from the demo MUSE
        were reproduced with RMSE median 0.024 mm, 90th percentile 0.061 mm, worst 0.107 mm
        (50: 0.058 / 0.123 / 0.261; 20 left up to 0.3 mm; ``benchmarks/bench_write.py``).
    """

    temperature: float = 0.0
    seed: int = 0
    impute_steps: int = 20
    method: str = "alg1"
    speed_cm_s: float = DEFAULT_SPEED_CM_S
    ramp_s: float = 0.3
    samples_per_s: float = 100.0
    basis_per_100_samples: int = 70
    layout: LayoutParams = field(default_factory=LayoutParams)
    connection: ConnectionParams = field(default_factory=ConnectionParams)


def usable_inputs(model: MultimodalVAE, inputs: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    """The largest subset of ``inputs`` the family accepts; dropped modalities are logged.

    Raises
    ------
    UsageError
        If the family accepts none of the given modalities.
    """
    given = tuple(m for m in MODALITIES if m in inputs)
    candidates = [s for s in model.accepted_inputs if set(s) <= set(given)]
    if not candidates:
        accepted = " or ".join("{" + ", ".join(s) + "}" for s in model.accepted_inputs)
        raise UsageError(
            f"{model.family} cannot use the given inputs {{{', '.join(given)}}}: it accepts "
            f"{accepted}"
        )
    # prefer more modalities; among equals, the family's own order (label before image for AVAE)
    best = max(candidates, key=len)
    dropped = [m for m in given if m not in best]
    if dropped:
        log.warning("%s uses %s; ignoring %s", model.family, list(best), dropped)
    return {m: inputs[m] for m in best}


@torch.no_grad()
def decode_letters(
    model: MultimodalVAE,
    inputs: dict[str, torch.Tensor],
    temperature: float = 0.0,
    seed: int = 0,
    impute_steps: int = 0,
) -> np.ndarray:
    """One generated trajectory per letter.

    Parameters
    ----------
    model : MultimodalVAE
    inputs : dict
        Per-letter model inputs, each with N rows (``label`` (N,), ``traj`` (N, 200), ``image``
        (N, 1, 28, 28)).
    temperature, seed, impute_steps : see :class:`GenerateParams`.

    Returns
    -------
    ndarray, shape (N, 100, 2)
        Normalised letter trajectories (y up), as the training data.
    """
    chosen = usable_inputs(model, inputs)
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(seed)
        out = model.generate(
            chosen, "traj", n=1, temperature=temperature, impute_steps=impute_steps
        )[0]
    return out.numpy().reshape(len(out), -1, 2).astype(np.float64)


def rest_to_rest_samples(
    points: np.ndarray, speed_cm_s: float, ramp_s: float, samples_per_s: float
) -> tuple[np.ndarray, float]:
    """Resample a path uniformly in time under a rest-to-rest speed profile.

    Parameters
    ----------
    points : ndarray, shape (P, 2)
        The path (centimetres).
    speed_cm_s : float
        Mean speed over the whole path (> 0).
    ramp_s : float
        Duration of the half-cosine speed-up and slow-down (>= 0).
    samples_per_s : float
        Output samples per second (> 0).

    Returns
    -------
    samples : ndarray, shape (n, 2)
    duration : float
        Seconds.
    """
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(steps)])
    length = arc[-1]
    if length <= 0:
        raise UsageError("the word trajectory has zero length: nothing to write")
    # a profile of plateau speed v with ramps r: length = v (T - r), mean speed = length / T
    duration = length / speed_cm_s
    ramp = min(ramp_s, duration / 2)
    plateau = length / (duration - ramp)
    n = max(3, int(np.ceil(duration * samples_per_s)) + 1)
    if n > MAX_DMP_SAMPLES:  # the DMP fit's time and memory grow with n squared
        raise UsageError(
            f"the word is {length:.1f} cm long: at generate.speed_cm_s={speed_cm_s:g} and "
            f"generate.samples_per_s={samples_per_s:g} its DMP would take {n:,} samples "
            f"({duration:.0f} s); accepted are at most {MAX_DMP_SAMPLES:,}: write faster or less"
        )
    t = np.linspace(0.0, duration, n)
    s = plateau * _ramped_distance(t, duration, ramp)
    s = np.clip(s * length / s[-1], 0.0, length)
    x = np.interp(s, arc, points[:, 0])
    y = np.interp(s, arc, points[:, 1])
    return np.stack([x, y], axis=1), duration


def _ramped_distance(t: np.ndarray, duration: float, ramp: float) -> np.ndarray:
    """Distance travelled at unit plateau speed with half-cosine ramps (closed form)."""
    if ramp == 0:
        return t.copy()

    def up(u):  # integral of (1 - cos(pi u / ramp)) / 2 from 0 to u
        return 0.5 * (u - ramp / np.pi * np.sin(np.pi * u / ramp))

    total = duration - ramp
    return np.where(
        t < ramp,
        up(t),
        np.where(t > duration - ramp, total - up(duration - t), up(ramp) + (t - ramp)),
    )


def infer_text(model: MultimodalVAE, inputs: dict[str, torch.Tensor]) -> str:
    """The letters the model reads from the inputs (S given the inputs), for a word given without
    its text (e.g. images only): the layout needs each letter's class.

    Read from the posterior mean of the given channels, without imputation: imputing sharpens
    each letter's probabilities to 0 or 1 and throws away the second readings that the word's
    context (:func:`read_in_context`) chooses among. On ten demo words from the test split's
    letter images this reads 5 right, against 2 with imputation and the letters' first readings.
    """
    if "label" not in model.generated_modalities:
        raise UsageError(
            f"{model.family} cannot read letters from its inputs: give the text too (text=...)"
        )
    chosen = usable_inputs(model, inputs)
    with torch.no_grad():
        probs = model.generate(chosen, "label")[0]
    return read_in_context(probs)


# Letters whose shape, once normalised for size and position, does not tell their kind: the
# capital and small forms of C O P S V W X Z, and a capital I and a small l (a vertical stroke).
SHAPE_TWINS = {**{c: c.swapcase() for c in "CcOoPpSsVvWwXxZz"}, "I": "l", "l": "I"}

# The label ranges of each kind of character (prg.data.alphabet: 0-9, A-Z, a-z).
_KIND_LABELS = (range(0, 10), range(10, 36), range(36, 62))


def read_in_context(probs: torch.Tensor) -> str:
    """The word a reader sees in per-letter class probabilities ``(n, 62)``.

    A word is written in one kind of character — small letters, capitals or digits — so each
    letter is read as its most probable character of the kind that makes the whole word most
    probable (the sum over letters of the log of each letter's best probability in that kind),
    as a reader reads a letter in its word: "DeII" becomes "bell" when b and l are those
    letters' most probable small letters, "ca5" becomes "cat", "jumP" becomes "jump". A letter
    counts the probability of its shape twin too (``SHAPE_TWINS``: P for p, I for l), since the
    shape cannot tell them apart. When two kinds are equally probable (a tie) each letter keeps
    its most probable character.
    """
    merged = probs.clone()
    for char, twin in SHAPE_TWINS.items():
        merged[:, char_to_label(char)] = (
            probs[:, char_to_label(char)] + probs[:, char_to_label(twin)]
        )
    logp = merged.clamp_min(1e-12).log()
    scores = [float(logp[:, kind.start : kind.stop].max(-1).values.sum()) for kind in _KIND_LABELS]
    ranked = sorted(scores, reverse=True)
    if math.isclose(ranked[0], ranked[1], rel_tol=1e-9, abs_tol=1e-9):
        labels = probs.argmax(-1)
    else:
        kind = _KIND_LABELS[scores.index(ranked[0])]
        labels = merged[:, kind.start : kind.stop].argmax(-1) + kind.start
    return "".join(label_to_char(int(i)) for i in labels)


def check_inputs(text: str, inputs: dict[str, torch.Tensor]) -> None:
    """One clear error for unsupported characters, no inputs, or a channel whose letter count
    differs from the text's."""
    letters = [c for c in text if c != " "]
    text_to_labels("".join(letters))
    if not inputs:
        raise UsageError("no inputs: give the word through at least one channel")
    options = {"image": "images", "traj": "trajectories", "label": "text"}  # the user's names
    for modality, value in inputs.items():
        if len(value) != len(letters):
            raise UsageError(
                f"{options.get(modality, modality)}= gives {len(value)} letters but the text "
                f"{text!r} has {len(letters)} letters"
            )


def write_word(
    model: MultimodalVAE,
    text: str,
    inputs: dict[str, torch.Tensor],
    params: GenerateParams | None = None,
) -> tuple[WordTrajectory, np.ndarray]:
    """Generate a word with ``model`` and fit one DMP to the whole word.

    Parameters
    ----------
    model : MultimodalVAE
    text : str
        The word's letters (0-9, A-Z, a-z) with spaces between words: used for the layout.
    inputs : dict
        Per-letter model inputs, one row per non-space character of ``text``: ``label``
        (the S channel, e.g. :func:`label_inputs`), ``traj``, ``image`` — any subset.
    params : GenerateParams, optional

    Returns
    -------
    word : WordTrajectory
        Points, segments, text, timing and the fitted DMP (``word.dmp``).
    rollout : ndarray, shape (n, 2)
        The DMP's rollout on the demonstration's time grid.
    """
    params = params or GenerateParams()
    check_inputs(text, inputs)
    trajs = decode_letters(model, inputs, params.temperature, params.seed, params.impute_steps)
    return compose_word(trajs, text, params)


def compose_word(
    letters: np.ndarray, text: str, params: GenerateParams | None = None
) -> tuple[WordTrajectory, np.ndarray]:
    """The final processing map and the DMP on decoded letters (the second half of
    :func:`write_word`).

    Parameters
    ----------
    letters : ndarray, shape (N, k, 2)
        Normalised letter trajectories (y up), one per non-space character of ``text``.
    text : str
    params : GenerateParams, optional

    Returns
    -------
    word, rollout : as :func:`write_word`.
    """
    params = params or GenerateParams()
    placed = layout_letters(list(letters), text, params.layout)
    connections = connect_sequence(
        placed, params.connection, method=params.method, breaks=word_breaks(text)
    )
    word = assemble_word(placed, connections, text, speed_cm_s=params.speed_cm_s)
    samples, duration = rest_to_rest_samples(
        word.points, params.speed_cm_s, params.ramp_s, params.samples_per_s
    )
    n_basis = basis_count(len(samples), per_100_points=params.basis_per_100_samples)
    dmp = fit_dmp(samples, tau=duration, n_basis=n_basis)
    word.dmp = dmp.to_dict()
    word.duration_s = duration
    return word, rollout(dmp)


def clean_text(text: str, on_unknown: str = "error", key: str = "text") -> str:
    """``text`` ready to write: words separated by single spaces, unsupported characters handled.

    Parameters
    ----------
    text : str
    on_unknown : {"error", "skip"}
        ``"error"``: one error listing every character outside 0-9, A-Z, a-z (spaces aside);
        ``"skip"``: drop them (logged) and write the rest.
    key : str
        The option the text came from, for the message when it is longer than
        :data:`prg.checks.MAX_TEXT_LETTERS` letters.

    Raises
    ------
    UsageError
        For an unsupported character with ``on_unknown="error"``, an unknown ``on_unknown``, or
        nothing left to write.
    """
    if on_unknown not in ("error", "skip"):
        raise UsageError(f"on_unknown {on_unknown!r}: choose error or skip")
    words = text.split()
    unknown = unsupported_chars("".join(words))
    if unknown and on_unknown == "error":
        text_to_labels("".join(words))  # raises, listing them
    if unknown:
        log.warning("skipping unsupported characters %s", ", ".join(map(repr, unknown)))
        words = ["".join(c for c in w if c not in unknown) for w in words]
    cleaned = " ".join(w for w in words if w)
    if not cleaned:
        raise UsageError(f"text {text!r} has no letters to write: accepted are 0-9, A-Z and a-z")
    return check_text_length(cleaned, key)


def label_inputs(text: str) -> dict[str, torch.Tensor]:
    """The S channel of ``text``: one class id per non-space character."""
    letters = "".join(c for c in text if c != " ")
    return {"label": torch.as_tensor(text_to_labels(letters), dtype=torch.long)}
