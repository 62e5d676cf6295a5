"""The long-format response file: one row per trial, the exact columns of each study.

This module is the single definition of the response CSV that the study's web page writes and
``prg-study analyze`` reads. It imports nothing heavy (no pandas, no NumPy) so that the page
builder and the simulator can share it.

Both studies share :data:`COMMON_COLUMNS`; each adds its own outcome columns in the middle:

=====================  ========  ==========================================================
column                 type      accepted values
=====================  ========  ==========================================================
participant_id         str       non-empty (e.g. Prolific's ``PROLIFIC_PID``)
session_id             str       may be empty
study                  str       ``turing`` or ``readability`` (aliases: ``1``/``2``)
list_id                str       counterbalancing list (study 2: ``A``/``B``); may be empty
trial                  int       >= 0, position of the trial in the participant's sequence
word                   str       non-empty, the word shown
robot_index            int       study 1: 0-4, position of the robot's sample (0-based)
chosen_index           int       study 1: 0-4, position the participant picked (0-based)
chose_robot            bool      study 1: ``chosen_index == robot_index``
confidence             int       study 1: 1-5 (very low, low, neutral, high, very high)
writer                 str       study 2: ``human`` or ``robot``, who wrote the word shown
typed_text             str       study 2: what the participant typed (may be empty)
correct                bool      study 2: typed_text matches word (trimmed, case-insensitive)
rt_ms                  float     >= 0, response time in milliseconds; may be empty
is_attention_check     bool      true for attention-check trials (kept, flagged, not deleted)
attention_pass         bool      attention-check rows: passed?; empty on other rows
timestamp              str       ISO 8601 time of the response
app_version            str       version of the web page that recorded the row (ends in
                                 ``-pilot`` from a pilot build; ``simulated`` from the simulator)
seed                   int       the counterbalancing seed; may be empty
=====================  ========  ==========================================================

Booleans are written ``true``/``false`` (``1``/``0``, ``yes``/``no``, ``True``/``False`` are
read too). On attention-check rows the outcome columns may be empty.

Only the columns the analysis cannot do without are *required*
(:data:`STUDY1_REQUIRED`, :data:`STUDY2_REQUIRED`); a missing optional column is named in the
report, and extra columns are ignored. Study 1 may give either ``chose_robot`` or both
``robot_index`` and ``chosen_index``; study 2 either ``correct`` or ``typed_text``.
"""

from __future__ import annotations

from dataclasses import dataclass

TURING = "turing"
READABILITY = "readability"
STUDY_KINDS: tuple[str, ...] = (TURING, READABILITY)
#: Values of the ``study`` column read as each kind.
STUDY_ALIASES: dict[str, str] = {
    "turing": TURING,
    "1": TURING,
    "study1": TURING,
    "study 1": TURING,
    "readability": READABILITY,
    "2": READABILITY,
    "study2": READABILITY,
    "study 2": READABILITY,
}
WRITERS: tuple[str, ...] = ("human", "robot")

#: ``app_version`` of simulated participants' rows (``prg-study simulate``).
SIMULATED_VERSION = "simulated"
#: How a pilot build's ``app_version`` ends (``prg-study build --pilot``).
PILOT_SUFFIX = "-pilot"
#: Where a row comes from, by its ``app_version``: people answering a study, a pilot build, or
#: the simulator. A file holds one of them (the analysis never mixes them).
ORIGINS: tuple[str, ...] = ("study", "pilot", "simulated")


def origin_of(app_version: str) -> str:
    """The origin (one of :data:`ORIGINS`) of a row with this ``app_version``."""
    version = str(app_version).strip()
    if version == SIMULATED_VERSION:
        return "simulated"
    return "pilot" if version.endswith(PILOT_SUFFIX) else "study"


N_OPTIONS = 5  #: samples shown per study-1 trial (4 human, 1 robot)
CONFIDENCE_RANGE: tuple[int, int] = (1, 5)
CONFIDENCE_LABELS: tuple[str, ...] = ("very low", "low", "neutral", "high", "very high")
TRUE_STRINGS = frozenset({"true", "1", "yes", "y", "t", "1.0"})
FALSE_STRINGS = frozenset({"false", "0", "no", "n", "f", "0.0"})


@dataclass(frozen=True)
class Column:
    """One response column: its name, type, what is accepted, and when it must be filled."""

    name: str
    type: str  #: "str" | "int" | "float" | "bool"
    accepted: str  #: human-readable accepted values, used in validation messages
    description: str


COLUMNS: dict[str, Column] = {
    c.name: c
    for c in (
        Column("participant_id", "str", "a non-empty id", "participant (Prolific PID)"),
        Column("session_id", "str", "any text", "session of the participant"),
        Column("study", "str", "turing or readability", "which study the row belongs to"),
        Column("list_id", "str", "any text (study 2: A or B)", "counterbalancing list"),
        Column("trial", "int", "an integer >= 0", "position of the trial for the participant"),
        Column("word", "str", "a non-empty word", "the word shown"),
        Column("robot_index", "int", "an integer 0-4", "position of the robot's sample"),
        Column("chosen_index", "int", "an integer 0-4", "position the participant picked"),
        Column("chose_robot", "bool", "true/false (1/0)", "the participant picked the robot"),
        Column("confidence", "int", "an integer 1-5", "confidence in the choice"),
        Column("writer", "str", "human or robot", "who wrote the word shown"),
        Column("typed_text", "str", "any text", "what the participant typed"),
        Column("correct", "bool", "true/false (1/0)", "typed text matches the word"),
        Column("rt_ms", "float", "a number >= 0", "response time (ms)"),
        Column("is_attention_check", "bool", "true/false (1/0)", "attention-check trial"),
        Column("attention_pass", "bool", "true/false (1/0) or empty", "attention check passed"),
        Column("timestamp", "str", "ISO 8601 text", "time of the response"),
        Column("app_version", "str", "any text", "version of the web page"),
        Column("seed", "int", "an integer or empty", "counterbalancing seed"),
    )
}

COMMON_HEAD: tuple[str, ...] = ("participant_id", "session_id", "study", "list_id", "trial", "word")
COMMON_TAIL: tuple[str, ...] = (
    "rt_ms",
    "is_attention_check",
    "attention_pass",
    "timestamp",
    "app_version",
    "seed",
)
COMMON_COLUMNS: tuple[str, ...] = COMMON_HEAD + COMMON_TAIL

#: The exact columns, in order, of a study-1 (Turing-like test) response file.
STUDY1_COLUMNS: tuple[str, ...] = (
    *COMMON_HEAD,
    "robot_index",
    "chosen_index",
    "chose_robot",
    "confidence",
    *COMMON_TAIL,
)
#: The exact columns, in order, of a study-2 (readability) response file.
STUDY2_COLUMNS: tuple[str, ...] = (
    *COMMON_HEAD,
    "writer",
    "typed_text",
    "correct",
    *COMMON_TAIL,
)
STUDY_COLUMNS: dict[str, tuple[str, ...]] = {TURING: STUDY1_COLUMNS, READABILITY: STUDY2_COLUMNS}

#: Columns without which study 1 cannot be analysed (plus chose_robot or both indices).
STUDY1_REQUIRED: tuple[str, ...] = ("participant_id", "word", "confidence")
#: Columns without which study 2 cannot be analysed (plus correct or typed_text).
STUDY2_REQUIRED: tuple[str, ...] = ("participant_id", "word", "writer")
STUDY_REQUIRED: dict[str, tuple[str, ...]] = {TURING: STUDY1_REQUIRED, READABILITY: STUDY2_REQUIRED}


def study_kind(value: str) -> str | None:
    """The study kind a ``study`` cell names (``None`` when it names none)."""
    return STUDY_ALIASES.get(str(value).strip().lower())


def kind_from_columns(columns: list[str] | tuple[str, ...]) -> str | None:
    """Guess the study from the columns present (``None`` when both or neither fit)."""
    cols = set(columns)
    one = bool(cols & {"chose_robot", "chosen_index", "confidence"})
    two = bool(cols & {"writer", "typed_text", "correct"})
    if one != two:
        return TURING if one else READABILITY
    return None


def normalise_text(text: str) -> str:
    """How typed text is compared with the word: trimmed, case-folded, inner spaces collapsed."""
    return " ".join(str(text).split()).casefold()
