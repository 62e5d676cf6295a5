"""Study designs: the counterbalanced trial lists of a study.

A study is one YAML file under ``conf/study/`` (``turing.yaml``, ``readability.yaml``), read by
:func:`load_study` into a :class:`StudySettings` (both in :mod:`studies.design_config`, whose
names are importable from here too). Everything a participant sees is decided here,
offline and seeded, as one :class:`Row` per participant (the page picks its row, see
:func:`assign_row`):

* **Study 1, Turing-like** (``kind: turing``, :func:`turing_rows`): per word one robot sample and
  ``foils`` human samples; word order shuffled per participant; the robot's position (0 to
  ``foils``, left to right; the page numbers them from 1) taken from a Latin square (:func:`robot_positions`): every position
  equally often within each participant (when the number of words is a multiple of the number of
  options) and, for every word, equally often across participants (when the number of participants
  is); the human foils are sampled per trial from the word's writers.
* **Study 2, readability** (``kind: readability``, :func:`readability_rows`): two lists A/B that
  swap which half of the words is shown human- and which robot-written (:func:`split_lists`),
  alternated over participants, so that each word x writer is seen equally often; the human
  writer of each word rotates over participants; word order shuffled per participant.

Attention checks (instructed responses) are inserted after a given trial (:func:`with_checks`);
they are flagged in the responses, never deleted.

All functions here are pure: same arguments, same result.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from prg.errors import UsageError
from studies.design_config import (
    ANALYSIS_KEYS,
    CANVAS_PX,
    CODE_RE,
    CONFIDENCE_LABELS,
    DEFAULT_CONSENT,
    DEFAULT_INSTRUCTIONS,
    KINDS,
    MAX_FOILS,
    MAX_HUMAN_WRITERS,
    MAX_PARTICIPANTS,
    MAX_REDIRECT_DELAY_MS,
    MAX_SEED,
    MAX_TRIALS,
    MAX_WORD_LENGTH,
    MAX_WORDS,
    NAME_RE,
    ON_LIFT,
    PROLIFIC_URL,
    URL_SCHEMES,
    WORD_RE,
    AttentionCheck,
    StudySettings,
    default_completion_code,
    load_study,
    normalise_answer,
    study_from_dict,
)
from studies.overrides import apply_overrides, parse_override
from studies.stimuli import ROBOT

__all__ = [  # with, re-exported, the names of studies.design_config and ROBOT
    "ANALYSIS_KEYS",
    "CANVAS_PX",
    "CODE_RE",
    "CONFIDENCE_LABELS",
    "DEFAULT_CONSENT",
    "DEFAULT_INSTRUCTIONS",
    "KINDS",
    "MAX_FOILS",
    "MAX_HUMAN_WRITERS",
    "MAX_PARTICIPANTS",
    "MAX_REDIRECT_DELAY_MS",
    "MAX_SEED",
    "MAX_TRIALS",
    "MAX_WORDS",
    "MAX_WORD_LENGTH",
    "NAME_RE",
    "ON_LIFT",
    "PROLIFIC_URL",
    "ROBOT",
    "URL_SCHEMES",
    "WORD_RE",
    "AttentionCheck",
    "Row",
    "StudySettings",
    "Trial",
    "apply_overrides",
    "assign_row",
    "balance_notes",
    "default_completion_code",
    "design_rows",
    "fnv1a32",
    "latin_square",
    "load_study",
    "normalise_answer",
    "parse_override",
    "readability_rows",
    "robot_positions",
    "split_lists",
    "study_from_dict",
    "turing_rows",
    "with_checks",
    "word_orders",
]


# ---------------------------------------------------------------------------- trials and rows
@dataclass(frozen=True)
class Trial:
    """One screen of the study.

    Attributes
    ----------
    word : str
    options : tuple of str
        Writer ids of the samples shown, in screen order (``"robot"`` for the robot's). Study 1:
        ``foils + 1`` of them; study 2: one.
    robot_index : int or None
        Study 1: 0-based position of the robot's sample (screen label ``robot_index + 1``);
        study 2: None.
    is_attention_check : bool
    expect : dict or None
        The passing response of an attention check.
    instruction : str or None
        The attention check's instruction.
    """

    word: str
    options: tuple[str, ...]
    robot_index: int | None = None
    is_attention_check: bool = False
    expect: dict | None = None
    instruction: str | None = None

    @property
    def writer(self) -> str:
        """Study 2: ``"robot"`` or ``"human"``."""
        return ROBOT if self.options[0] == ROBOT else "human"


@dataclass(frozen=True)
class Row:
    """Everything one participant sees, in order.

    Attributes
    ----------
    row : int
        0-based index in the trial list (what :func:`assign_row` returns).
    list_id : str
        Study 1: ``row-001`` ...; study 2: the list name (A or B).
    trials : tuple of Trial
    """

    row: int
    list_id: str
    trials: tuple[Trial, ...]


def latin_square(n: int, rng: np.random.Generator | None = None) -> np.ndarray:
    """An ``n x n`` Latin square of 0..n-1: every symbol once per row and once per column.

    Cyclic (``(r + c) mod n``); with ``rng`` its rows, columns and symbols are permuted, which
    keeps it Latin.

    Returns
    -------
    ndarray of int, shape (n, n)
    """
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n}")
    square = (np.arange(n)[:, None] + np.arange(n)[None, :]) % n
    if rng is not None:
        square = square[rng.permutation(n)][:, rng.permutation(n)]
        square = rng.permutation(n)[square]
    return square


def robot_positions(n_participants: int, n_words: int, n_options: int, seed: int) -> np.ndarray:
    """The robot's 0-based screen position per participant and word (words in config order).

    Row ``p`` of a seeded Latin square of size ``n_options``, taken at ``p mod n_options``,
    gives word ``w`` the position ``square[p mod n_options, w mod n_options]``. Hence each
    position comes up ``n_words / n_options`` times per participant and, for every word,
    ``n_participants / n_options`` times across participants (exactly, when those divide;
    otherwise within one).

    Returns
    -------
    ndarray of int, shape (n_participants, n_words), values in 0..n_options - 1
    """
    square = latin_square(n_options, np.random.default_rng([seed, 1]))
    p = np.arange(n_participants)[:, None] % n_options
    w = np.arange(n_words)[None, :] % n_options
    return square[p, w]


def word_orders(n_participants: int, n_words: int, seed: int) -> np.ndarray:
    """An independent seeded shuffle of the word indices per participant.

    Returns
    -------
    ndarray of int, shape (n_participants, n_words)
    """
    return np.stack(
        [np.random.default_rng([seed, 2, p]).permutation(n_words) for p in range(n_participants)]
    ).reshape(n_participants, n_words)


def with_checks(trials: Sequence[Trial], checks: Sequence[tuple[int, Trial]]) -> tuple[Trial, ...]:
    """Insert attention-check trials: ``(after_trial, trial)`` goes after that many word trials
    (checks with the same ``after_trial`` keep their order)."""
    out: list[Trial] = []
    pending = sorted(enumerate(checks), key=lambda item: (item[1][0], item[0]))
    k = 0
    for i in range(len(trials) + 1):
        while k < len(pending) and pending[k][1][0] == i:
            out.append(pending[k][1][1])
            k += 1
        if i < len(trials):
            out.append(trials[i])
    return tuple(out)


def _writers(writers: Mapping[str, Sequence[str]], word: str, needed: int) -> list[str]:
    ids = sorted(set(writers.get(word, ())) - {ROBOT})
    if len(ids) < needed:
        raise UsageError(f"word {word!r} has {len(ids)} human writers, the design needs {needed}")
    return ids


def turing_rows(config: StudySettings, writers: Mapping[str, Sequence[str]]) -> tuple[Row, ...]:
    """Study 1's trial list: one :class:`Row` per participant.

    Parameters
    ----------
    config : StudySettings
        ``kind == "turing"``.
    writers : mapping of str to sequence of str
        Human writer ids available per word (at least ``foils`` each; the first
        ``human_writers`` in sorted order are used).

    Returns
    -------
    tuple of Row
        Row ``p``: the words in a seeded order, per word ``foils`` human writers sampled without
        replacement, and the robot at :func:`robot_positions`.
    """
    words = config.words
    pools = {w: _writers(writers, w, config.foils)[: config.human_writers] for w in words}
    positions = robot_positions(config.participants, len(words), config.n_options, config.seed)
    orders = word_orders(config.participants, len(words), config.seed)
    rows = []
    for p in range(config.participants):
        rng = np.random.default_rng([config.seed, 3, p])
        main = [_turing_trial(config, pools, int(w), int(positions[p, w]), rng) for w in orders[p]]
        rows.append(Row(p, f"row-{p + 1:03d}", _with_checks_of(main, config)))
    return tuple(rows)


def _turing_trial(
    config: StudySettings,
    pools: Mapping[str, Sequence[str]],
    w: int,
    position: int,
    rng: np.random.Generator,
) -> Trial:
    """Word ``w`` with ``foils`` writers drawn from its pool and the robot at ``position``."""
    word = config.words[w]
    foils = [str(x) for x in rng.choice(pools[word], config.foils, replace=False)]
    return Trial(word, (*foils[:position], ROBOT, *foils[position:]), robot_index=position)


def _with_checks_of(main: Sequence[Trial], config: StudySettings) -> tuple[Trial, ...]:
    """``main`` with the config's attention checks inserted. A check repeats one of the
    participant's own screens (its ``word``'s, else the one just before it) so that it shows
    nothing new: a second look at another sample could give the robot away (study 1) or prime
    the reading (study 2)."""
    checks = []
    for c in config.attention_checks:
        if c.word is not None:
            base = next(t for t in main if t.word == c.word)
        else:
            base = main[max(c.after_trial - 1, 0)]
        check = replace(base, is_attention_check=True, expect=c.expect, instruction=c.instruction)
        checks.append((c.after_trial, check))
    return with_checks(main, checks)


def split_lists(words: Sequence[str], lists: Sequence[str], seed: int) -> dict[str, dict[str, str]]:
    """Study 2's lists: per list name, ``{word: "human" | "robot"}``.

    A seeded half of the words is human-written in the first list and robot-written in the
    second; the other half the reverse.
    """
    n = len(words)
    if n % 2:
        raise UsageError(f"the readability lists need an even number of words, got {n}")
    human_first = set(np.random.default_rng([seed, 4]).permutation(n)[: n // 2].tolist())
    first = {w: ("human" if i in human_first else ROBOT) for i, w in enumerate(words)}
    second = {w: (ROBOT if v == "human" else "human") for w, v in first.items()}
    return {lists[0]: first, lists[1]: second}


def readability_rows(
    config: StudySettings, writers: Mapping[str, Sequence[str]]
) -> tuple[Row, ...]:
    """Study 2's trial list: one :class:`Row` per participant.

    Participant ``p`` gets list ``lists[p mod 2]``; its human-written words show writer
    ``pool[(p // 2 + word index) mod len(pool)]`` (every writer in turn); the words come in a
    seeded order per participant.

    Parameters
    ----------
    config : StudySettings
        ``kind == "readability"``.
    writers : mapping of str to sequence of str
        Human writer ids available per word (at least one; the first ``human_writers`` in
        sorted order are used).
    """
    words = config.words
    pools = {w: _writers(writers, w, 1)[: config.human_writers] for w in words}
    assignment = split_lists(words, config.lists, config.seed)
    orders = word_orders(config.participants, len(words), config.seed)
    rows = []
    for p in range(config.participants):
        list_id = config.lists[p % 2]

        def trial(w: int, source: str, p: int = p) -> Trial:
            pool = pools[words[w]]
            writer = ROBOT if source == ROBOT else pool[(p // 2 + w) % len(pool)]
            return Trial(words[w], (writer,))

        main = [trial(int(w), assignment[list_id][words[w]]) for w in orders[p]]
        rows.append(Row(p, list_id, _with_checks_of(main, config)))
    return tuple(rows)


def balance_notes(config: StudySettings) -> list[str]:
    """Where the counterbalancing can only be near-exact with these numbers (one line each)."""
    notes = []
    if config.kind == "turing":
        k = config.n_options
        if len(config.words) % k:
            notes.append(
                f"{len(config.words)} words are not a multiple of {k} options: the robot's "
                "positions differ by one within a participant"
            )
        if config.participants % k:
            notes.append(
                f"{config.participants} participants are not a multiple of {k} options: the "
                "robot's positions per word differ by one across participants"
            )
    elif config.participants % 2:
        notes.append(
            f"{config.participants} participants is odd: list {config.lists[0]} is used once "
            f"more than list {config.lists[1]}"
        )
    return notes


def design_rows(config: StudySettings, writers: Mapping[str, Sequence[str]]) -> tuple[Row, ...]:
    """:func:`turing_rows` or :func:`readability_rows`, by ``config.kind``."""
    return (turing_rows if config.kind == "turing" else readability_rows)(config, writers)


# ---------------------------------------------------------------------------- assignment
def fnv1a32(text: str) -> int:
    """32-bit FNV-1a hash of the UTF-8 bytes of ``text`` (the page computes the same)."""
    h = 0x811C9DC5
    for byte in text.encode("utf-8"):
        h ^= byte
        h = (h * 0x01000193) & 0xFFFFFFFF
    return h


def assign_row(participant_id: str, n_rows: int, salt: str = "") -> int:
    """The row a participant gets from their id (the page's rule when no ``row`` is given).

    ``fnv1a32(salt + ":" + participant_id) mod n_rows``, with the study's name as ``salt``: the
    same Prolific id always lands on the same row; over many ids rows fill about evenly.
    """
    if n_rows < 1:
        raise ValueError(f"n_rows must be >= 1, got {n_rows}")
    return fnv1a32(f"{salt}:{participant_id}") % n_rows
