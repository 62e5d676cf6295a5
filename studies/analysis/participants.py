"""Simulated participants with known truth, written in the response file's exact columns.

The answers follow a crossed logit model (:mod:`studies.analysis.crossed_logit`),
``logit P(answer) = b0 + u_participant + v_word`` with ``u ~ N(0, su^2)``, ``v ~ N(0, sv^2)``,
whose parameters are *calibrated* so that the stated truth holds on the probability scale:

- ``rate`` is the population-average probability (what the binomial test and the GEE
  estimate), not the rate of a median participant;
- ``icc`` is the share of the 0/1 answers' variance due to participants,
  ``Var_u(E[p | u]) / (rate (1 - rate))`` — the within-participant correlation of two answers,
  which is what the GEE's exchangeable working correlation estimates and what the power planner
  (:mod:`studies.analysis.power`) takes;
- ``word_icc`` the same for words.

Confidence ratings (study 1) are a latent normal cut at 1.5, 2.5, 3.5, 4.5, with a participant
share ``confidence_icc`` of the latent variance, shifted so their population mean is
``confidence_mean``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from datetime import datetime, timedelta, timezone

import numpy as np
import pandas as pd
from scipy import optimize, special, stats

from studies.analysis.crossed_logit import MAX_ICC, intercept, latent_parameters
from studies.analysis.schema import (
    N_OPTIONS,
    READABILITY,
    SIMULATED_VERSION,
    STUDY1_COLUMNS,
    STUDY2_COLUMNS,
    TURING,
)

DEFAULT_WORDS: tuple[str, ...] = (
    "bell",
    "cat",
    "jump",
    "joy",
    "house",
    "tree",
    "water",
    "music",
    "robot",
    "hand",
)
CONFIDENCE_CUTS = np.array([1.5, 2.5, 3.5, 4.5])
CONFIDENCE_LATENT_SD = 1.5
APP_VERSION = SIMULATED_VERSION

__all__ = [
    "APP_VERSION",
    "CONFIDENCE_CUTS",
    "CONFIDENCE_LATENT_SD",
    "DEFAULT_WORDS",
    "MAX_ICC",
    "Truth",
    "confidence_shift",
    "latent_parameters",
    "simulate_readability",
    "simulate_turing",
]


def confidence_shift(mean: float, sd: float = CONFIDENCE_LATENT_SD) -> float:
    """Latent location whose cut ratings (1-5) have population mean ``mean``."""
    if not 1 < mean < 5:
        raise ValueError(f"confidence mean {mean} is outside (1, 5)")
    return float(
        optimize.brentq(
            lambda s: 1 + stats.norm.cdf((s - CONFIDENCE_CUTS) / sd).sum() - mean, -20, 30
        )
    )


@dataclass
class Truth:
    """What the simulated participants were drawn from (written next to the CSV as JSON)."""

    kind: str
    participants: int
    words: list[str]
    seed: int
    rate: float | None = None  #: study 1: P(pick the robot); population average
    human_rate: float | None = None  #: study 2
    robot_rate: float | None = None  #: study 2
    icc: float = 0.0
    word_icc: float = 0.0
    confidence_mean: float | None = None
    confidence_icc: float | None = None
    inattentive: int = 0
    latent: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return asdict(self)


def _timestamps(rng: np.random.Generator, n: int, start: datetime, rt_ms: np.ndarray) -> list[str]:
    t = start + timedelta(seconds=float(rng.uniform(0, 86400)))
    out = []
    for rt in rt_ms:
        t = t + timedelta(milliseconds=float(rt) + 500)
        out.append(t.isoformat(timespec="milliseconds").replace("+00:00", "Z"))
    return out


def _check_positions(rng: np.random.Generator, n_trials: int, checks: int) -> set[int]:
    """Trials (never the first) that are attention checks."""
    if not checks:
        return set()
    picked = rng.choice(np.arange(1, n_trials), size=min(checks, n_trials - 1), replace=False)
    return set(picked.tolist())


def _rt(rng: np.random.Generator, n: int) -> np.ndarray:
    return np.round(rng.lognormal(math.log(4000), 0.5, n))


def _trials(
    rng: np.random.Generator,
    i: int,
    study: str,
    list_id: str,
    n_trials: int,
    checks: int,
    start: datetime,
    seed: int,
    careless: bool,
) -> list[tuple[bool, dict]]:
    """Participant ``i``'s trials in order: (is an attention check, the columns every trial has).

    ``checks`` of them (never the first) are attention checks, failed by a ``careless``
    participant."""
    check_at = _check_positions(rng, n_trials, checks)
    rts = _rt(rng, n_trials)
    stamps = _timestamps(rng, n_trials, start, rts)
    pid, sid = f"P{i + 1:04d}", f"S{i + 1:04d}"
    return [
        (
            t in check_at,
            dict(
                participant_id=pid,
                session_id=sid,
                study=study,
                list_id=list_id,
                trial=t,
                rt_ms=f"{rts[t]:.0f}",
                timestamp=stamps[t],
                app_version=APP_VERSION,
                seed=seed,
                is_attention_check=_bool(t in check_at),
                attention_pass=_bool(not careless) if t in check_at else "",
            ),
        )
        for t in range(n_trials)
    ]


def _bool(x) -> str:
    return "true" if bool(x) else "false"


def _check_common(participants: int, words: list[str]) -> None:
    if participants < 1:
        raise ValueError(f"participants {participants} must be >= 1")
    if len(words) < 1 or len(set(words)) != len(words):
        raise ValueError("words must be a non-empty list without repeats")


def simulate_turing(
    participants: int,
    rate: float,
    *,
    icc: float = 0.0,
    word_icc: float = 0.0,
    words: list[str] | tuple[str, ...] = DEFAULT_WORDS,
    confidence_mean: float = 3.0,
    confidence_icc: float = 0.1,
    attention_checks: int = 1,
    inattentive: int = 0,
    n_options: int = N_OPTIONS,
    seed: int = 0,
) -> tuple[pd.DataFrame, Truth]:
    """Study 1 (Turing-like test): which of ``n_options`` samples did the robot write?

    Each participant sees every word once (order shuffled), the robot's sample at each position
    equally often (a shuffled Latin-square row), rates confidence 1-5, and gets
    ``attention_checks`` attention-check trials ("pick sample k"). ``inattentive`` extra
    participants answer at random and fail their checks (truth: the analysis excludes them).

    Returns
    -------
    frame : DataFrame
        :data:`~studies.analysis.schema.STUDY1_COLUMNS`, values as the web page writes them.
    truth : Truth
    """
    words = list(words)
    _check_common(participants, words)
    rng = np.random.default_rng(seed)
    b0, su, sv = latent_parameters(rate, icc, word_icc)
    shift = confidence_shift(confidence_mean)
    c_between = CONFIDENCE_LATENT_SD * math.sqrt(confidence_icc)
    c_within = CONFIDENCE_LATENT_SD * math.sqrt(1 - confidence_icc)
    v = rng.normal(0, sv, len(words)) if sv > 0 else np.zeros(len(words))
    start = datetime(2025, 3, 1, tzinfo=timezone.utc)
    rows = []
    total = participants + inattentive
    for i in range(total):
        careless = i >= participants
        u = rng.normal(0, su) if su > 0 else 0.0
        a = rng.normal(0, c_between)
        order = rng.permutation(len(words))
        positions = rng.permutation(np.resize(rng.permutation(n_options), len(words)))
        n_trials = len(words) + attention_checks
        trials = _trials(rng, i, TURING, "", n_trials, attention_checks, start, seed, careless)
        w_iter = iter(zip(order, positions))
        for is_check, base in trials:
            if is_check:
                target = int(rng.integers(n_options))
                passed = not careless
                chosen = (
                    target if passed else int((target + rng.integers(1, n_options)) % n_options)
                )
                rows.append(
                    dict(
                        base,
                        word="attention-check",
                        robot_index=target,
                        chosen_index=chosen,
                        chose_robot="",
                        confidence="",
                    )
                )
                continue
            j, pos = next(w_iter)
            p = 1.0 / n_options if careless else special.expit(b0 + u + v[j])
            chose = rng.random() < p
            chosen = int(pos) if chose else int((pos + rng.integers(1, n_options)) % n_options)
            if careless:
                conf = int(rng.integers(1, 6))
            else:
                latent = shift + a + rng.normal(0, c_within)
                conf = int(1 + (latent > CONFIDENCE_CUTS).sum())
            rows.append(
                dict(
                    base,
                    word=words[j],
                    robot_index=int(pos),
                    chosen_index=chosen,
                    chose_robot=_bool(chose),
                    confidence=conf,
                )
            )
    frame = pd.DataFrame(rows)[list(STUDY1_COLUMNS)]
    truth = Truth(
        kind=TURING,
        participants=participants,
        words=words,
        seed=seed,
        rate=rate,
        icc=icc,
        word_icc=word_icc,
        confidence_mean=confidence_mean,
        confidence_icc=confidence_icc,
        inattentive=inattentive,
        latent=dict(b0=b0, su=su, sv=sv, word_effects=v.tolist(), confidence_shift=shift),
    )
    return frame, truth


def _misspell(word: str, rng: np.random.Generator) -> str:
    letters = "abcdefghijklmnopqrstuvwxyz"
    if len(word) == 0:
        return "x"
    i = int(rng.integers(len(word)))
    choices = [c for c in letters if c != word[i].lower()]
    return word[:i] + choices[int(rng.integers(len(choices)))] + word[i + 1 :]


def simulate_readability(
    participants: int,
    robot_rate: float,
    human_rate: float | None = None,
    *,
    icc: float = 0.0,
    word_icc: float = 0.0,
    words: list[str] | tuple[str, ...] = DEFAULT_WORDS,
    attention_checks: int = 1,
    inattentive: int = 0,
    seed: int = 0,
) -> tuple[pd.DataFrame, Truth]:
    """Study 2 (readability): type the word you see; lists A/B swap who wrote which half.

    Participants alternate between list A (first half of the words by the human, second half by
    the robot) and list B (the swap). A participant's effect ``u`` is shared by both writers
    (the within-participant design the paired analysis uses). ``human_rate`` defaults to
    ``robot_rate`` (equally readable). Attention checks show a typeset word to copy.

    Returns
    -------
    frame : DataFrame
        :data:`~studies.analysis.schema.STUDY2_COLUMNS`.
    truth : Truth
    """
    words = list(words)
    _check_common(participants, words)
    human_rate = robot_rate if human_rate is None else human_rate
    rng = np.random.default_rng(seed)
    _, su, sv = latent_parameters((robot_rate + human_rate) / 2, icc, word_icc)
    b_h, b_r = intercept(human_rate, su, sv), intercept(robot_rate, su, sv)
    v = rng.normal(0, sv, len(words)) if sv > 0 else np.zeros(len(words))
    half = len(words) // 2
    start = datetime(2025, 3, 8, tzinfo=timezone.utc)
    rows = []
    for i in range(participants + inattentive):
        careless = i >= participants
        list_id = "A" if i % 2 == 0 else "B"
        u = rng.normal(0, su) if su > 0 else 0.0
        order = rng.permutation(len(words))
        n_trials = len(words) + attention_checks
        trials = _trials(
            rng, i, READABILITY, list_id, n_trials, attention_checks, start, seed, careless
        )
        w_iter = iter(order)
        for is_check, base in trials:
            if is_check:
                passed = not careless
                typed = "attention" if passed else "asdf"
                rows.append(
                    dict(
                        base,
                        word="attention",
                        writer="",
                        typed_text=typed,
                        correct=_bool(passed),
                    )
                )
                continue
            j = int(next(w_iter))
            human = (j < half) == (list_id == "A")
            b = b_h if human else b_r
            p = 0.05 if careless else special.expit(b + u + v[j])
            ok = rng.random() < p
            typed = words[j] if ok else _misspell(words[j], rng)
            rows.append(
                dict(
                    base,
                    word=words[j],
                    writer="human" if human else "robot",
                    typed_text=typed,
                    correct=_bool(ok),
                )
            )
    frame = pd.DataFrame(rows)[list(STUDY2_COLUMNS)]
    truth = Truth(
        kind=READABILITY,
        participants=participants,
        words=words,
        seed=seed,
        human_rate=human_rate,
        robot_rate=robot_rate,
        icc=icc,
        word_icc=word_icc,
        inattentive=inattentive,
        latent=dict(b_human=b_h, b_robot=b_r, su=su, sv=sv, word_effects=v.tolist()),
    )
    return frame, truth
