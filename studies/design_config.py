"""A study's YAML file (``conf/study/*.yaml``), read and checked into a :class:`StudySettings`.

:func:`load_study` reads the file and applies ``key=value`` overrides
(:func:`studies.overrides.apply_overrides`, the ``--set`` of ``prg-study build``);
:func:`study_from_dict` checks every key and value and fills in the defaults, raising
:class:`prg.errors.UsageError` with one line that names the bad key. The ``render`` section is
checked as :class:`studies.stimuli.RenderStyle` takes it, the ``analysis`` section as
``prg-study analyze`` reads it (:mod:`studies.analysis.config`).

The designs built from a :class:`StudySettings` are in :mod:`studies.design`.
"""

from __future__ import annotations

import hashlib
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import yaml

from prg.errors import UsageError
from studies.overrides import apply_overrides
from studies.stimuli import DELAYED_MAX_SIZE, RenderStyle, sets_delayed_strokes

KINDS = ("turing", "readability")
WORD_RE = re.compile(r"^[A-Za-z]+$")
NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]*$")
ON_LIFT = ("restart", "flag")

DEFAULT_CONSENT = (
    "This study is about handwriting. It takes about 5 minutes. Your answers are anonymous "
    "and are only used for research; you may stop at any time by closing the page."
)
DEFAULT_INSTRUCTIONS = {
    "turing": (
        "For each word you will see five handwritten samples of it. Four were written by people "
        "and one by a robot. Click the sample you think the robot wrote, then say how confident "
        "you are."
    ),
    "readability": (
        "For each trial you will see one handwritten word. Type the word you read and press "
        "Enter (or click Next)."
    ),
}
CONFIDENCE_LABELS = ("very low", "low", "neutral", "high", "very high")
PROLIFIC_URL = "https://app.prolific.com/submissions/complete?cc={code}"

# Limits of a study file: beyond them a build takes minutes and gigabytes, or the page breaks.
MAX_PARTICIPANTS = 10_000
MAX_WORDS = 200
MAX_WORD_LENGTH = 30
MAX_HUMAN_WRITERS = 100
MAX_FOILS = 9  #: at most 10 samples on one screen
MAX_TRIALS = 200_000  #: participants x trials each, all in trials.json (about 4 s to design)
MAX_SEED = 2**32 - 1
MAX_REDIRECT_DELAY_MS = 60_000
CANVAS_PX = (50, 4000)  #: capture page canvas, CSS pixels
CODE_RE = re.compile(r"^[A-Za-z0-9_-]{1,64}$")
URL_SCHEMES = ("http", "https")


@dataclass(frozen=True)
class AttentionCheck:
    """An instructed-response trial shown after ``after_trial`` word trials.

    Attributes
    ----------
    after_trial : int
        Number of word trials before it (0: first of all).
    instruction : str
        What the participant is told to do instead of the usual task.
    expect : dict
        The passing response: ``{"chosen_index": k}`` and optionally ``"confidence": c``
        (study 1, 0-based; the YAML gives ``choose_sample: k + 1``, the number shown on screen)
        or ``{"typed_text": "word"}`` (study 2).
    word : str or None
        Whose screen it repeats (None: the word trial just before it, or the first).
    """

    after_trial: int
    instruction: str
    expect: dict
    word: str | None = None


@dataclass(frozen=True)
class StudySettings:
    """A study as described by its YAML file (see ``conf/study/turing.yaml`` for every key).

    Attributes
    ----------
    name : str
        Folder name: the bundle is built into ``studies/<name>/build/``.
    kind : {"turing", "readability"}
    words : tuple of str
        The words written by the robot and by every human writer (letters only).
    human_writers : int
        Human writers per word (the paper's group 1: 10).
    foils : int
        Study 1: human samples shown beside the robot's (4); the trial has ``foils + 1`` options.
    participants : int
        Counterbalanced rows generated (the paper: 50 for study 1, 30 for study 2).
    lists : tuple of str
        Study 2: the two list names (A, B).
    seed : int
    delayed_strokes : bool
        True (default): the robot writes its words with delayed strokes (``prg-write``
        ``delayed_strokes=true``: the i's and j's dotted, the t's and f's crossed after the
        cursive word) and the capture page lets the human writers add their dots and bars after
        the word in the same way; False: the paper's single stroke for both.
    equivalence_margin : float
        Fixed before data collection: study 1 the margin around chance, study 2 the margin on
        the human - robot difference in reading success.
    alpha : float
    attention_checks : tuple of AttentionCheck
    robot : dict
        ``family``, ``ckpt``, ``dir`` (ready word trajectories instead of writing them) and
        ``write_overrides`` (a list of ``prg-write`` overrides).
    render : dict
        :class:`studies.stimuli.RenderStyle` fields.
    human : dict
        ``dirs``: folders of human samples; ``accept_lifted``: use samples written with a pen
        lift (default False).
    page : dict
        ``title``, ``consent``, ``instructions``, ``confidence_labels``.
    completion : dict
        ``code``, ``url`` (``{code}`` is replaced), ``redirect_delay_ms``.
    save : dict
        ``download`` (offer the CSV at the end) and ``post_url`` (POST it there; null: don't).
    capture : dict
        The capture page: ``on_lift`` (restart | flag), ``post_url``, ``canvas_width``,
        ``canvas_height`` (CSS pixels), ``delayed_max_size`` (with ``delayed_strokes``: a
        stroke after the word is a dot or bar when its bounding box is no taller than this
        fraction of the word's height and no wider than twice it; a larger one is a pen lift).
    source : str
        The YAML file it was read from (or ``"<dict>"``).
    """

    name: str
    kind: str
    words: tuple[str, ...]
    human_writers: int = 10
    foils: int = 4
    participants: int = 50
    lists: tuple[str, ...] = ("A", "B")
    seed: int = 0
    delayed_strokes: bool = True
    equivalence_margin: float = 0.05
    alpha: float = 0.05
    attention_checks: tuple[AttentionCheck, ...] = ()
    robot: dict = field(default_factory=dict)
    render: dict = field(default_factory=dict)
    human: dict = field(default_factory=dict)
    page: dict = field(default_factory=dict)
    completion: dict = field(default_factory=dict)
    save: dict = field(default_factory=dict)
    capture: dict = field(default_factory=dict)
    source: str = "<dict>"

    @property
    def n_options(self) -> int:
        """Samples per study-1 trial (robot + foils)."""
        return self.foils + 1

    @property
    def chance(self) -> float:
        """Study 1: the rate of picking the robot by guessing, ``1 / n_options``."""
        return 1.0 / self.n_options

    def min_writers(self) -> int:
        """Human writers each word needs before the study can run."""
        return self.human_writers


_SECTIONS = {
    "robot": {
        "family": "muse",
        "ckpt": None,
        "dir": None,
        "write_overrides": [],
        "hands": "per_word",
    },
    "render": {},
    "human": {"dirs": [], "accept_lifted": False},
    "page": {},
    "completion": {"code": None, "url": PROLIFIC_URL, "redirect_delay_ms": 3000},
    "save": {"download": True, "post_url": None},
    "capture": {
        "on_lift": "restart",
        "post_url": None,
        "canvas_width": 900,
        "canvas_height": 300,
        "delayed_max_size": DELAYED_MAX_SIZE,
    },
}
#: Sections without defaults: the keys they accept (render: studies.stimuli.RenderStyle's).
_FREE_SECTIONS = {"page": ("title", "consent", "instructions", "confidence_labels")}
#: Keys of the ``analysis`` section (see studies.analysis.config).
ANALYSIS_KEYS = (
    "alpha",
    "chance",
    "equivalence_margin",
    "exclude_failed_attention",
    "margin_source",
    "n_options",
    "neutral",
)
_TOP = {
    "name",
    "kind",
    "words",
    "human_writers",
    "foils",
    "participants",
    "lists",
    "seed",
    "delayed_strokes",
    "equivalence_margin",
    "alpha",
    "attention_checks",
    "analysis",
    *_SECTIONS,
}


def _int(
    doc: Mapping, key: str, default: int | None, minimum: int, maximum: int | None = None
) -> int:
    value = doc.get(key, default)
    if (
        isinstance(value, bool)
        or not isinstance(value, int)
        or value < minimum
        or (maximum is not None and value > maximum)
    ):
        accepted = f">= {minimum}" if maximum is None else f"from {minimum} to {maximum}"
        raise UsageError(f"{key} must be an integer {accepted}, got {value!r}")
    return value


def _url(value: Any, key: str, *, code: bool = False) -> str | None:
    """An ``http(s)://host/...`` URL or None; with ``code``, one holding ``{code}``."""
    if value is None:
        return None
    accepted = "an http:// or https:// URL" + (" holding {code}" if code else "") + " or null"
    try:
        parts = urlsplit(value.strip()) if isinstance(value, str) else None
    except ValueError:
        parts = None
    if (
        parts is None
        or parts.scheme.lower() not in URL_SCHEMES
        or not parts.hostname
        or any(ch.isspace() or not ch.isprintable() for ch in value.strip())
    ):
        raise UsageError(f"{key} must be {accepted}, got {value!r}")
    if code and "{code}" not in value:
        raise UsageError(
            f"{key} {value!r} has no {{code}} placeholder for the completion code: accepted is "
            f"{accepted}, e.g. {PROLIFIC_URL}"
        )
    return value.strip()


def _section(key: str, value: Any, defaults: dict) -> dict:
    """A section's settings over its defaults; an unknown key is named."""
    if not isinstance(value, Mapping):
        raise UsageError(f"{key} must be a mapping of settings, got {value!r}")
    known = set(defaults) if defaults else set(_FREE_SECTIONS.get(key, ()))
    unknown = sorted(set(value) - known) if known else []
    if unknown:
        raise UsageError(
            f"{key}: unknown key {unknown[0]!r}: accepted are {', '.join(sorted(known))}"
        )
    return {**defaults, **value}


def _check_sections(sections: dict) -> None:
    """The settings of every section: types, ranges, URLs (the one place they are checked)."""
    RenderStyle.from_dict(sections["render"])
    robot, completion = sections["robot"], sections["completion"]
    family = robot["family"]
    if not isinstance(family, str) or not NAME_RE.match(family):
        raise UsageError(f"robot.family must be a model family name like muse, got {family!r}")
    for key in ("ckpt", "dir"):
        if robot[key] is not None and not (isinstance(robot[key], str) and robot[key].strip()):
            raise UsageError(f"robot.{key} must be a path or null, got {robot[key]!r}")
    if robot["hands"] not in ("per_word", "one"):
        raise UsageError(f"robot.hands must be per_word or one, got {robot['hands']!r}")
    overrides = robot["write_overrides"]
    if not isinstance(overrides, list) or not all(isinstance(o, str) for o in overrides):
        raise UsageError(
            "robot.write_overrides must be a list of prg-write overrides (key=value texts)"
        )
    clash = next((o for o in overrides if sets_delayed_strokes(o)), None)
    if clash is not None:
        raise UsageError(
            f"robot.write_overrides: {clash!r}: set the study's top-level delayed_strokes "
            "instead (it decides for the robot and the human writers alike)"
        )
    for section, key in (("human", "accept_lifted"), ("save", "download")):
        if not isinstance(sections[section][key], bool):
            raise UsageError(
                f"{section}.{key} must be true or false, got {sections[section][key]!r}"
            )
    completion["url"] = _url(completion["url"], "completion.url", code=True)
    delay = completion["redirect_delay_ms"]
    if (
        isinstance(delay, bool)
        or not isinstance(delay, int)
        or not 0 <= delay <= MAX_REDIRECT_DELAY_MS
    ):
        raise UsageError(
            f"completion.redirect_delay_ms must be an integer from 0 to {MAX_REDIRECT_DELAY_MS} "
            f"(milliseconds), got {delay!r}"
        )
    for section in ("save", "capture"):
        sections[section]["post_url"] = _url(sections[section]["post_url"], f"{section}.post_url")
    for key in ("canvas_width", "canvas_height"):
        value = sections["capture"][key]
        low, high = CANVAS_PX
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
            raise UsageError(
                f"capture.{key} must be an integer from {low} to {high} (CSS pixels), got {value!r}"
            )
    size = sections["capture"]["delayed_max_size"]
    if (
        isinstance(size, bool)
        or not isinstance(size, int | float)
        or not (math.isfinite(size) and 0 < size <= 1)
    ):
        raise UsageError(
            "capture.delayed_max_size must be a number in (0, 1] (a fraction of the word's "
            f"height), got {size!r}"
        )
    page = sections["page"]
    for key in ("title", "consent", "instructions"):
        if page.get(key) is not None and not isinstance(page[key], str):
            raise UsageError(f"page.{key} must be text, got {page[key]!r}")
    labels = page.get("confidence_labels")
    if labels is not None and (
        not isinstance(labels, list) or not all(isinstance(x, str) and x.strip() for x in labels)
    ):
        raise UsageError(f"page.confidence_labels must be a list of 5 texts, got {labels!r}")


def _check_analysis(doc: Mapping, kind: str) -> None:
    """The ``analysis`` section as ``prg-study analyze`` reads it: known keys, valid values."""
    analysis = doc.get("analysis") or {}
    unknown = sorted(set(analysis) - set(ANALYSIS_KEYS))
    if unknown:
        raise UsageError(
            f"analysis: unknown key {unknown[0]!r}: accepted are {', '.join(ANALYSIS_KEYS)}"
        )
    try:
        from studies.analysis.config import config_from_mapping
    except ImportError:  # the analysis package is optional for building
        return
    cfg = config_from_mapping({**doc, **analysis, "kind": kind}, "analysis")
    if kind == "turing" and cfg.margin is not None and not cfg.margin < cfg.chance:
        raise UsageError(
            f"analysis: equivalence_margin {cfg.margin:g} must be below chance {cfg.chance:g}: "
            "the band chance ± margin must stay above 0"
        )


def _float(doc: Mapping, key: str, default: float, low: float, high: float) -> float:
    value = doc.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int | float) or not low < value < high:
        raise UsageError(f"{key} must be a number in ({low}, {high}), got {value!r}")
    return float(value)


def study_from_dict(doc: Mapping[str, Any], source: str = "<dict>") -> StudySettings:
    """Validate a parsed study document; raises :class:`UsageError` naming the bad key."""
    if not isinstance(doc, Mapping):
        raise UsageError("a study file must hold a mapping of keys (name, kind, words, ...)")
    unknown = sorted(set(doc) - _TOP)
    if unknown:
        raise UsageError(f"unknown key {unknown[0]!r}: accepted are {', '.join(sorted(_TOP))}")
    name = doc.get("name")
    if not isinstance(name, str) or not NAME_RE.match(name) or len(name) > 64:
        raise UsageError(f"name must be 1-64 letters, digits, - or _ (a folder name), got {name!r}")
    kind = doc.get("kind")
    if kind not in KINDS:
        raise UsageError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    words = doc.get("words")
    if not isinstance(words, list) or not words or len(words) > MAX_WORDS:
        raise UsageError(
            f"words must be a list of 1 to {MAX_WORDS} words, e.g. words: [bell, cat, jump]"
            + (f", got {len(words)}" if isinstance(words, list) else f", got {words!r}")
        )
    for word in words:
        if not isinstance(word, str) or not WORD_RE.match(word) or len(word) > MAX_WORD_LENGTH:
            raise UsageError(
                f"words: {word!r} is not a word of 1 to {MAX_WORD_LENGTH} letters a-z/A-Z"
            )
    if len(set(words)) != len(words):
        dup = next(w for w in words if words.count(w) > 1)
        raise UsageError(f"words: {dup!r} is listed twice")
    foils = _int(doc, "foils", 4, 1, MAX_FOILS)
    human_writers = _int(doc, "human_writers", 10, 1, MAX_HUMAN_WRITERS)
    if kind == "turing" and human_writers < foils:
        raise UsageError(
            f"human_writers ({human_writers}) must be at least foils ({foils}): each trial shows "
            "foils different human writers"
        )
    lists = doc.get("lists", ["A", "B"])
    if (
        not isinstance(lists, list)
        or len(lists) != 2
        or not all(isinstance(x, str) and NAME_RE.match(x) for x in lists)
        or lists[0] == lists[1]
    ):
        raise UsageError(f"lists must be two different names, e.g. [A, B], got {lists!r}")
    delayed = doc.get("delayed_strokes", True)
    if not isinstance(delayed, bool):
        raise UsageError(
            "delayed_strokes must be true (the robot dots its i's and crosses its t's and the "
            f"writers add their dots and bars after the word) or false (one stroke), got {delayed!r}"
        )
    if kind == "readability" and len(words) % 2:
        raise UsageError(
            f"a readability study needs an even number of words (half human, half robot per "
            f"list), got {len(words)}"
        )
    sections = {}
    for key, defaults in _SECTIONS.items():
        sections[key] = _section(key, doc.get(key) or {}, defaults)
    if not isinstance(doc.get("analysis") or {}, Mapping):
        raise UsageError("analysis must be a mapping of settings (read by prg-study analyze)")
    _check_sections(sections)
    if sections["capture"]["on_lift"] not in ON_LIFT:
        raise UsageError(
            f"capture.on_lift must be one of {', '.join(ON_LIFT)}, "
            f"got {sections['capture']['on_lift']!r}"
        )
    if not isinstance(sections["robot"]["write_overrides"], list):
        raise UsageError("robot.write_overrides must be a list of prg-write overrides")
    dirs = sections["human"]["dirs"]
    if not isinstance(dirs, list) or not all(isinstance(d, str) and d for d in dirs):
        raise UsageError(f"human.dirs must be a list of folders, got {dirs!r}")
    code = sections["completion"]["code"]
    if code is None:
        sections["completion"]["code"] = default_completion_code(name, doc.get("seed", 0))
    elif not isinstance(code, str) or not CODE_RE.match(code):
        raise UsageError(
            f"completion.code must be 1-64 letters, digits, - or _ (it goes into the "
            f"completion URL), got {code!r}"
        )
    config = StudySettings(
        name=name,
        kind=kind,
        words=tuple(words),
        human_writers=human_writers,
        foils=foils,
        participants=_int(doc, "participants", 50, 1, MAX_PARTICIPANTS),
        lists=tuple(lists),
        seed=_int(doc, "seed", 0, 0, MAX_SEED),
        delayed_strokes=delayed,
        equivalence_margin=_float(doc, "equivalence_margin", 0.05, 0.0, 1.0),
        alpha=_float(doc, "alpha", 0.05, 0.0, 0.5),
        robot=sections["robot"],
        render=sections["render"],
        human=sections["human"],
        page=_page(sections["page"], kind, name),
        completion=sections["completion"],
        save=sections["save"],
        capture=sections["capture"],
        source=source,
    )
    if kind == "turing" and not config.equivalence_margin < config.chance:
        raise UsageError(
            f"equivalence_margin {config.equivalence_margin:g} must be below chance "
            f"{config.chance:g} (1 / (foils + 1)): the band chance ± margin must stay above 0"
        )
    _check_analysis(doc, kind)
    checks = _checks(doc.get("attention_checks") or [], config)
    trials = config.participants * (len(config.words) + len(checks))
    if trials > MAX_TRIALS:
        raise UsageError(
            f"participants ({config.participants}) x trials each ({len(config.words) + len(checks)}) "
            f"is {trials} trials; at most {MAX_TRIALS} (the build and trials.json grow with it)"
        )
    return replace(config, attention_checks=checks)


def _page(page: dict, kind: str, name: str) -> dict:
    out = {
        "title": page.get("title") or "Handwriting study",
        "consent": page.get("consent") or DEFAULT_CONSENT,
        "instructions": page.get("instructions") or DEFAULT_INSTRUCTIONS[kind],
        "confidence_labels": list(page.get("confidence_labels") or CONFIDENCE_LABELS),
    }
    if len(out["confidence_labels"]) != 5:
        raise UsageError("page.confidence_labels must name the 5 points of the scale")
    return out


def _checks(raw: Any, config: StudySettings) -> tuple[AttentionCheck, ...]:
    if not isinstance(raw, list):
        raise UsageError("attention_checks must be a list of {after_trial, instruction, expect}")
    checks = []
    for i, item in enumerate(raw):
        where = f"attention_checks[{i}]"
        if not isinstance(item, Mapping):
            raise UsageError(f"{where} must be a mapping with after_trial, instruction, expect")
        extra = sorted(set(item) - {"after_trial", "instruction", "expect", "word"})
        if extra:
            raise UsageError(f"{where}: unknown key {extra[0]!r}")
        after = item.get("after_trial")
        if isinstance(after, bool) or not isinstance(after, int):
            raise UsageError(f"{where}.after_trial must be an integer, got {after!r}")
        if not 0 <= after <= len(config.words):
            raise UsageError(
                f"{where}.after_trial must be between 0 and {len(config.words)} (the number of "
                f"words), got {after}"
            )
        instruction = item.get("instruction")
        if not isinstance(instruction, str) or not instruction.strip():
            raise UsageError(f"{where}.instruction must be a non-empty text")
        expect = item.get("expect")
        expect_raw = dict(expect) if isinstance(expect, Mapping) else {}
        word = item.get("word")
        if word is not None and word not in config.words:
            raise UsageError(f"{where}.word {word!r} is not one of the study's words")
        allowed = {"choose_sample", "confidence"} if config.kind == "turing" else {"typed_text"}
        if set(expect_raw) - allowed:
            extra = sorted(set(expect_raw) - allowed)[0]
            raise UsageError(
                f"{where}.expect: unknown key {extra!r}: accepted are {sorted(allowed)}"
            )
        if config.kind == "turing":
            k = expect_raw.get("choose_sample")
            if isinstance(k, bool) or not isinstance(k, int) or not 1 <= k <= config.n_options:
                raise UsageError(
                    f"{where}.expect must be {{choose_sample: K}}: the sample numbered K on "
                    f"screen, K in 1..{config.n_options}"
                )
            expect = {"chosen_index": k - 1}
            if "confidence" in expect_raw:
                level = expect_raw["confidence"]
                if isinstance(level, bool) or level not in (1, 2, 3, 4, 5):
                    raise UsageError(f"{where}.expect.confidence must be 1-5, got {level!r}")
                expect["confidence"] = level
        else:
            text = expect_raw.get("typed_text")
            if not isinstance(text, str) or not normalise_answer(text):
                raise UsageError(f"{where}.expect must be {{typed_text: WORD}}")
            expect = {"typed_text": text}
        checks.append(AttentionCheck(after, instruction.strip(), expect, word))
    return tuple(checks)


def load_study(path: str | Path, overrides: Sequence[str] = ()) -> StudySettings:
    """Read and validate a study YAML file (plus ``key=value`` overrides).

    Raises
    ------
    UsageError
        One line naming the file and the bad key or value.
    """
    path = Path(path)
    try:
        doc = yaml.safe_load(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise UsageError(f"{path}: no such study file (e.g. conf/study/turing.yaml)") from None
    except (OSError, UnicodeDecodeError) as err:
        raise UsageError(f"{path}: cannot read the study file ({err})") from None
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        raise UsageError(f"{path}: not valid YAML{where}") from None
    if not isinstance(doc, dict):
        raise UsageError(f"{path}: a study file must hold a mapping of keys (name, kind, ...)")
    try:
        return study_from_dict(apply_overrides(doc, overrides), source=str(path))
    except UsageError as err:
        raise UsageError(f"{path}: {err}") from None


def default_completion_code(name: str, seed: int) -> str:
    """A stable completion code for a study without one: 8 upper-case hex digits."""
    return hashlib.sha256(f"prg-study:{name}:{seed}".encode()).hexdigest()[:8].upper()


def normalise_answer(text: str) -> str:
    """How typed words are compared in study 2 (the rule of
    ``studies.analysis.schema.normalise_text``, which the page follows too): trimmed,
    case-folded, inner white space collapsed."""
    return " ".join(str(text).split()).casefold()
