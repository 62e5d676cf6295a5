"""The simulation's truth beside the estimates of a report on simulated participants.

``prg-study simulate`` writes the truth it drew the participants from next to the responses
(``<name>.truth.json``, a :class:`~studies.analysis.participants.Truth`). :func:`read_truth`
reads it back and :func:`with_truth` gives each study of an analysis its truth and adds a
``truth`` column to the study's tables: beside
each estimate, the value of the quantity it estimates under the simulation's model
(:mod:`studies.analysis.crossed_logit`, ``logit P = b + u_participant + v_word``):

- a rate over participants and words (the binomial tests, the GEE, participants' mean rate):
  the population-average rate the simulation was calibrated to;
- the crossed mixed logit's intercept, a *typical* participant's rate on a typical word:
  ``expit(b)``; its terms on the logit scale: ``b``, the writer log-odds ratio, the SDs;
- a word's rate: the average over participants of ``expit(b + u + v_word)``, with that
  word's drawn effect;
- mean confidence: the simulation's population mean; the median of participant means (the
  signed-rank test): the expected rating of a median participant.

The truth describes attentive participants: the simulation's inattentive ones answer at random,
and the analysis leaves them out unless told to keep them.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import fields, replace
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import special, stats

from prg.errors import UsageError
from studies.analysis.analyze import Analysis, StudyAnalysis
from studies.analysis.crossed_logit import NODES, WEIGHTS
from studies.analysis.participants import CONFIDENCE_CUTS, CONFIDENCE_LATENT_SD, Truth
from studies.analysis.schema import READABILITY, STUDY_KINDS, TURING

__all__ = ["describe", "headline", "read_truth", "truth_path_for", "with_truth"]


def truth_path_for(responses: str | Path) -> Path:
    """Where ``prg-study simulate`` writes the truth of ``responses``: ``<name>.truth.json``."""
    return Path(responses).with_suffix(".truth.json")


def read_truth(path: str | Path, what: str = "--truth") -> Truth:
    """The :class:`Truth` in a ``<name>.truth.json`` file (UsageError naming ``what`` if not)."""
    p = Path(path)
    accepted = "the .truth.json that prg-study simulate wrote beside the responses"
    if not p.is_file():
        raise UsageError(f"{what} {path}: no such file (expected {accepted})")
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise UsageError(f"{what} {path}: not valid JSON (expected {accepted})") from None
    names = {f.name for f in fields(Truth)}
    if (
        not isinstance(doc, dict)
        or doc.get("kind") not in STUDY_KINDS
        or not names >= set(doc)
        or not isinstance(doc.get("latent"), dict)
        or not isinstance(doc.get("words"), list)
    ):
        raise UsageError(f"{what} {path}: not a simulation's truth (expected {accepted})")
    return Truth(**doc)


def _average_rate(b: float, su: float, v: float = 0.0) -> float:
    """E_u[expit(b + u + v)], u ~ N(0, su^2): a word's rate over participants."""
    return float(WEIGHTS @ special.expit(b + su * NODES + v))


def _word_effects(truth: Truth) -> dict[str, float]:
    return dict(zip(truth.words, truth.latent.get("word_effects", []), strict=False))


def _typical_confidence(truth: Truth) -> float:
    """The expected rating of a median participant (participant effect 0)."""
    within = CONFIDENCE_LATENT_SD * math.sqrt(1 - (truth.confidence_icc or 0.0))
    shift = truth.latent["confidence_shift"]
    return 1.0 + float(stats.norm.cdf((shift - CONFIDENCE_CUTS) / within).sum())


def _test_truth(kind: str, test: str, hypothesis: str, truth: Truth) -> float:
    """The true value of what the test named ``test`` estimates."""
    lat = truth.latent
    if kind == TURING:
        if hypothesis.startswith("H2"):
            return (
                _typical_confidence(truth) if test.startswith("Wilcoxon") else truth.confidence_mean
            )
        return float(special.expit(lat["b0"])) if test.startswith("crossed mixed") else truth.rate
    if test.startswith("crossed mixed"):  # the writer term, a log-odds ratio
        return lat["b_robot"] - lat["b_human"]
    return truth.robot_rate - truth.human_rate


def _term_truth(kind: str, term: str, truth: Truth) -> float:
    """The true value of a crossed-mixed-logit term (logit scale)."""
    lat = truth.latent
    if term == "Intercept":
        return lat["b0"] if kind == TURING else lat["b_human"]
    if term == "sd(participant_id)":
        return lat["su"]
    if term == "sd(word)":
        return lat["sv"]
    if term.startswith("C(writer"):
        return lat["b_robot"] - lat["b_human"]
    return math.nan


def _word_truth(kind: str, row, truth: Truth) -> float:
    """A word's (and writer's) true population-average rate."""
    v = _word_effects(truth).get(row.word)
    if v is None:
        return math.nan
    lat = truth.latent
    if kind == TURING:
        return _average_rate(lat["b0"], lat["su"], v)
    return _average_rate(lat["b_robot" if row.writer == "robot" else "b_human"], lat["su"], v)


def _study_with_truth(st: StudyAnalysis, truth: Truth, path: str) -> StudyAnalysis:
    tests = st.tests.assign(
        truth=[
            _test_truth(st.kind, r.test, r.hypothesis, truth)
            for r in st.tests.itertuples(index=False)
        ]
    )
    per_word = st.per_word.assign(
        truth=[_word_truth(st.kind, r, truth) for r in st.per_word.itertuples(index=False)]
    )
    mixed = st.mixed
    if mixed is not None and "term" in mixed:
        mixed = mixed.assign(truth=[_term_truth(st.kind, t, truth) for t in mixed["term"]])
    return replace(st, tests=tests, per_word=per_word, mixed=mixed, truth=truth, truth_path=path)


def with_truth(analysis: Analysis, truths: Sequence[tuple[Truth, str | Path]]) -> Analysis:
    """``analysis`` of simulated responses with each simulation's truth beside the estimates of
    its study: ``truths`` holds (truth, the file it was read from) pairs, one per study; each
    study gets its ``truth`` and a ``truth`` column in its tests, per-word and mixed-model
    tables.

    Raises
    ------
    prg.errors.UsageError
        The responses are not simulated, a truth is of a study they do not hold (or of other
        words), or two truths are of the same study.
    """
    studies = {st.kind: st for st in analysis.studies}
    done: dict[str, str] = {}
    for truth, path in truths:
        if analysis.origin != "simulated":
            raise UsageError(
                f"--truth {path}: {analysis.source} holds no simulated rows (app_version "
                "'simulated'); a simulation's truth goes only with its own responses"
            )
        st = studies.get(truth.kind)
        if st is None:
            raise UsageError(
                f"--truth {path}: the truth of a {truth.kind} simulation, but the responses "
                f"analysed are {', '.join(studies)}"
            )
        if truth.kind in done:
            raise UsageError(
                f"--truth {path}: a second truth for the {truth.kind} study (the first: "
                f"{done[truth.kind]}); give one per study"
            )
        unknown = sorted(set(st.data["word"]) - set(truth.words))
        if unknown:
            raise UsageError(
                f"--truth {path}: the {truth.kind} responses have words the simulation did not "
                f"draw ({', '.join(map(str, unknown[:5]))}); give the truth written with them"
            )
        done[truth.kind] = str(path)
        studies[truth.kind] = _study_with_truth(st, truth, str(path))
    return replace(analysis, studies=list(studies.values()))


def headline(st: StudyAnalysis) -> pd.DataFrame:
    """The main estimates of a study with a truth (:func:`with_truth`) beside it: quantity,
    truth, estimate [95 % CI], whether the interval holds the truth, how it was estimated."""
    from studies.analysis.stats import proportion_ci

    rows = []

    def add(quantity: str, true: float, est: float, lo: float, hi: float, how: str) -> None:
        inside = "yes" if lo <= true <= hi else "**no**"
        rows.append(
            {
                "quantity": quantity,
                "truth": f"{true:.3f}",
                "estimate [95 % CI]": f"{est:.3f} [{lo:.3f}, {hi:.3f}]",
                "truth in CI": inside if np.isfinite(lo) else "–",
                "estimated by": how,
            }
        )

    def from_test(quantity: str, name: str | None) -> None:
        hit = st.tests[st.tests["test"] == name]
        if len(hit) and np.isfinite(hit["estimate"].iloc[0]):
            r = hit.iloc[0]
            add(quantity, r.truth, r.estimate, r.ci_low, r.ci_high, str(r.test))

    v = st.verdict
    if st.kind == TURING:
        from_test("rate of picking the robot's sample", v.get("h1_primary"))
        neutral = st.config.neutral
        from_test("mean confidence (1-5)", f"one-sample t-test vs {neutral:g} on participant means")
        return pd.DataFrame(rows)
    from_test("success rate: robot minus human", v.get("primary"))
    for writer, true in (("human", st.truth.human_rate), ("robot", st.truth.robot_rate)):
        y = st.data.loc[st.data["writer"] == writer, "correct"].dropna()
        if len(y):
            k, n = int(y.sum()), len(y)
            lo, hi = proportion_ci(k, n)
            add(f"{writer} success rate", true, k / n, lo, hi, "Wilson CI, trials independent")
    return pd.DataFrame(rows)


def describe(truth: Truth) -> str:
    """The simulation's settings in one line (for the report's banner)."""
    if truth.kind == READABILITY:
        rates = f"success rates human {truth.human_rate:g}, robot {truth.robot_rate:g}"
    else:
        rates = (
            f"rate of picking the robot {truth.rate:g}, mean confidence {truth.confidence_mean:g}"
        )
    extra = f", {truth.inattentive} inattentive" if truth.inattentive else ""
    return (
        f"{truth.participants} participants{extra}, {len(truth.words)} words, {rates}, "
        f"ICC {truth.icc:g}, word ICC {truth.word_icc:g}, seed {truth.seed}"
    )
