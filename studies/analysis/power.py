"""Power and sample size for both studies (``prg-study power turing|readability``).

Study 1 (Turing-like test): exact power of the binomial TOST of ``chance ± margin`` for ``n``
independent trials (:func:`binomial_tost_power`; exact power is a saw-tooth in ``n``, so
:func:`binomial_tost_sample_size` returns the ``n`` from which power *stays* above the target).
Trials are not independent: :func:`participants_needed` converts trials to participants with
a variance-components design effect,

``Var(mean) = p (1 - p) [icc / P + word_icc / W + (1 - icc - word_icc) / (P W)]``

for ``P`` participants each answering all ``W`` words, where ``icc``/``word_icc`` are the
participant and word shares of the 0/1 answers' variance (the ICC the GEE reports as its working
correlation). With few words the word term puts a floor under the variance that no number of
participants removes.

Study 2 (readability): power of the paired TOST (and non-inferiority test) on per-participant
success-rate differences, robot minus human, each participant reading ``trials_per_writer``
words per writer. The SD of the differences comes from the same crossed logit model the
simulator uses (:mod:`studies.analysis.crossed_logit`), and the TOST power is computed exactly for
normal differences by integrating over the sample SD (:func:`paired_tost_power`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import integrate, special, stats

from studies.analysis.crossed_logit import NODES, WEIGHTS, intercept, latent_parameters

DEFAULT_ICC = 0.10
DEFAULT_WORD_ICC = 0.005


# --------------------------------------------------------------------------- study 1


def binomial_tost_power(
    n: int | np.ndarray, rate: float, chance: float = 0.2, margin: float = 0.05, alpha: float = 0.05
) -> float | np.ndarray:
    """Exact power of the binomial TOST of ``chance ± margin`` with ``n`` independent trials.

    Equivalence is shown for ``k_low <= k <= k_high`` where ``P(X >= k_low | chance - margin)
    <= alpha`` and ``P(X <= k_high | chance + margin) <= alpha``; power is
    ``P(k_low <= X <= k_high | rate)``. Vectorised over ``n``.

    Reference: ``statsmodels.stats.proportion.power_binom_tost(low, upp, n, p_alt=rate,
    alpha=alpha)``.
    """
    n_arr = np.atleast_1d(np.asarray(n, dtype=float))
    low, upp = chance - margin, chance + margin
    k_low = stats.binom.isf(alpha, n_arr, low) + 1  # smallest k with P(X >= k | low) <= alpha
    k_hi = stats.binom.ppf(alpha, n_arr, upp)  # smallest k with P(X <= k | upp) >= alpha
    k_hi = np.where(stats.binom.cdf(k_hi, n_arr, upp) <= alpha, k_hi, k_hi - 1)
    pw = stats.binom.cdf(k_hi, n_arr, rate) - stats.binom.cdf(k_low - 1, n_arr, rate)
    pw = np.where(k_hi >= k_low, np.clip(pw, 0.0, 1.0), 0.0)
    return float(pw[0]) if np.ndim(n) == 0 else pw


@dataclass(frozen=True)
class TrialsNeeded:
    """Trials for a binomial TOST: first ``n`` reaching the power, and ``n`` from which it stays."""

    first: int | None
    stable: int | None


def binomial_tost_sample_size(
    rate: float,
    chance: float = 0.2,
    margin: float = 0.05,
    alpha: float = 0.05,
    power: float = 0.8,
    n_max: int = 200_000,
) -> TrialsNeeded:
    """Independent trials the exact binomial TOST needs to reach ``power``.

    ``stable`` is the smallest ``n`` with power >= target for every larger ``n`` checked (up
    to twice the normal-approximation size plus 500), the figure to plan with; ``first`` the
    smallest ``n`` that reaches it once. ``None`` when ``rate`` is outside the margin (power
    tends to 0) or ``n_max`` is not enough.
    """
    if not abs(rate - chance) < margin:
        return TrialsNeeded(None, None)
    z = stats.norm.ppf(1 - alpha) + stats.norm.ppf(1 - (1 - power) / (2 if rate == chance else 1))
    gap = margin - abs(rate - chance)
    approx = rate * (1 - rate) * (z / gap) ** 2
    n_hi = int(min(n_max, 2 * approx + 500))
    ns = np.arange(1, n_hi + 1)
    pw = binomial_tost_power(ns, rate, chance, margin, alpha)
    ok = pw >= power
    if not ok.any():
        return TrialsNeeded(None, None)
    first = int(ns[np.argmax(ok)])
    below = np.nonzero(~ok)[0]
    stable = (
        int(ns[below[-1] + 1])
        if below.size and below[-1] + 1 < len(ns)
        else (first if not below.size else None)
    )
    return TrialsNeeded(first, stable)


def participants_needed(
    trials: float, words: int, icc: float = DEFAULT_ICC, word_icc: float = DEFAULT_WORD_ICC
) -> float:
    """Participants (each answering ``words`` trials) matching ``trials`` independent trials.

    Solves ``icc / P + word_icc / W + (1 - icc - word_icc) / (P W) = 1 / trials`` for ``P``;
    ``inf`` when the word term alone exceeds ``1 / trials`` (more words needed, not more
    participants). Returns the exact (fractional) value; round up to plan.
    """
    floor = word_icc / words
    need = 1.0 / trials - floor
    if need <= 0:
        return math.inf
    return (icc + (1 - icc - word_icc) / words) / need


def turing_plan(
    rates: Sequence[float] = (0.20, 0.22),
    powers: Sequence[float] = (0.8, 0.9),
    chance: float = 0.2,
    margin: float = 0.05,
    alpha: float = 0.05,
    words: Sequence[int] = (10, 20),
    icc: float = DEFAULT_ICC,
    word_icc: float = DEFAULT_WORD_ICC,
) -> pd.DataFrame:
    """Sample sizes for study 1's equivalence-to-chance test, one row per rate x power x words.

    Returns
    -------
    DataFrame
        Columns study, test, true_rate, chance, margin, alpha, target_power, trials (stable),
        trials_first, words, icc, word_icc, participants (rounded up; NaN when unreachable),
        power_achieved (at ``trials``).
    """
    rows = []
    for r in rates:
        for pw in powers:
            need = binomial_tost_sample_size(r, chance, margin, alpha, pw)
            for w in words:
                parts = (
                    participants_needed(need.stable, w, icc, word_icc) if need.stable else math.inf
                )
                rows.append(
                    dict(
                        study="turing",
                        test="exact binomial TOST vs chance",
                        true_rate=r,
                        chance=chance,
                        margin=margin,
                        alpha=alpha,
                        target_power=pw,
                        trials=need.stable,
                        trials_first=need.first,
                        words=w,
                        icc=icc,
                        word_icc=word_icc,
                        participants=math.ceil(parts) if math.isfinite(parts) else np.nan,
                        power_achieved=binomial_tost_power(need.stable, r, chance, margin, alpha)
                        if need.stable
                        else np.nan,
                    )
                )
    return pd.DataFrame(rows)


def turing_power_at(
    trials: Sequence[int] = (500,),
    rates: Sequence[float] = (0.20, 0.22),
    chance: float = 0.2,
    margin: float = 0.05,
    alpha: float = 0.05,
) -> pd.DataFrame:
    """Exact TOST power for given numbers of independent trials (e.g. the paper's 500)."""
    rows = [
        dict(
            study="turing",
            trials=n,
            true_rate=r,
            chance=chance,
            margin=margin,
            alpha=alpha,
            power=binomial_tost_power(n, r, chance, margin, alpha),
        )
        for n in trials
        for r in rates
    ]
    return pd.DataFrame(rows)


# --------------------------------------------------------------------------- study 2


def paired_difference_sd(
    human_rate: float,
    robot_rate: float,
    trials_per_writer: int = 5,
    icc: float = DEFAULT_ICC,
    word_icc: float = DEFAULT_WORD_ICC,
    words: int | None = None,
) -> float:
    """SD of a participant's success-rate difference (robot - human) under the crossed logit model.

    ``Var(d) = E[p_r (1 - p_r) + p_h (1 - p_h)] / m + Var_u(p_r(u) - p_h(u)) + 4 word_icc p (1 - p) / W``:
    binomial noise of ``m`` trials per writer, the part of the participant effect that does not
    cancel between writers, and the counterbalanced word sets (lists A/B see the word halves in
    opposite writings). ``words`` defaults to ``2 m``.
    """
    m = trials_per_writer
    w = words or 2 * m
    mean_rate = (human_rate + robot_rate) / 2
    _, su, sv = latent_parameters(mean_rate, icc, word_icc)
    b_h, b_r = intercept(human_rate, su, sv), intercept(robot_rate, su, sv)
    grid = su * NODES[:, None] + sv * NODES[None, :]
    p_h, p_r = special.expit(b_h + grid), special.expit(b_r + grid)
    binom = float(WEIGHTS @ (p_h * (1 - p_h) + p_r * (1 - p_r)) @ WEIGHTS) / m
    by_u = (p_r - p_h) @ WEIGHTS
    participant = float(WEIGHTS @ (by_u - (robot_rate - human_rate)) ** 2)
    word = 4 * word_icc * mean_rate * (1 - mean_rate) / w
    return math.sqrt(binom + participant + word)


def paired_tost_power(
    participants: int,
    sd: float,
    margin: float = 0.10,
    difference: float = 0.0,
    alpha: float = 0.05,
) -> float:
    """Exact power of the paired TOST (``-margin < mean difference < margin``) for normal differences.

    With ``n`` differences of SD ``sd`` and true mean ``difference``, equivalence is shown when
    ``|mean - 0| < margin - t_{1-alpha, n-1} s / sqrt(n)`` on both sides. The power integrates
    the normal probability of the mean over the chi distribution of the sample SD ``s``.

    Reference: matches a Monte Carlo of ``statsmodels.stats.weightstats.ttost_paired``.
    """
    n = int(participants)
    if n < 2:
        return 0.0
    dof = n - 1
    tc = stats.t.ppf(1 - alpha, dof)
    se = sd / math.sqrt(n)
    # s = sd * sqrt(u / dof), u ~ chi2(dof); the band is empty once tc s / sqrt(n) >= margin
    u_max = dof * (margin / (tc * se)) ** 2

    def f(u: float) -> float:
        half = margin - tc * se * math.sqrt(u / dof)
        return (
            stats.norm.cdf((half - difference) / se) - stats.norm.cdf((-half - difference) / se)
        ) * stats.chi2.pdf(u, dof)

    spread = 12 * math.sqrt(2 * dof)  # chi2(dof) has mean dof and SD sqrt(2 dof)
    lo, hi = max(0.0, dof - spread), min(u_max, dof + spread)
    if hi <= lo:
        return 0.0
    val, _ = integrate.quad(f, lo, hi, limit=200)
    return float(min(max(val, 0.0), 1.0))


def noninferiority_power(
    participants: int, sd: float, margin: float = 0.10, difference: float = 0.0, alpha: float = 0.05
) -> float:
    """Power of the one-sided paired t-test of ``difference > -margin`` (noncentral t).

    Reference: ``statsmodels.stats.power.TTestPower().power(effect_size=(difference + margin) / sd,
    nobs=n, alpha=alpha, alternative="larger")``.
    """
    n = int(participants)
    if n < 2:
        return 0.0
    dof = n - 1
    nc = (difference + margin) / (sd / math.sqrt(n))
    return float(stats.nct.sf(stats.t.ppf(1 - alpha, dof), dof, nc))


def _smallest(f, target: float, lo: int = 3, n_max: int = 1_000_000) -> int | None:
    """Smallest n >= lo with f(n) >= target (f increasing), by doubling then bisection."""
    hi = max(lo, 8)
    while f(hi) < target:
        if hi >= n_max:
            return None
        lo, hi = hi + 1, min(2 * hi, n_max)
    while lo < hi:
        mid = (lo + hi) // 2
        if f(mid) >= target:
            hi = mid
        else:
            lo = mid + 1
    return lo


def readability_plan(
    rates: Sequence[float] = (0.80,),
    differences: Sequence[float] = (0.0, 0.05),
    powers: Sequence[float] = (0.8, 0.9),
    margin: float = 0.10,
    alpha: float = 0.05,
    words: int = 10,
    icc: float = DEFAULT_ICC,
    word_icc: float = DEFAULT_WORD_ICC,
) -> pd.DataFrame:
    """Participants for study 2's paired TOST and non-inferiority test.

    ``rates`` are human success rates; the robot's is ``rate + difference``; each participant
    reads ``words / 2`` words per writer. One row per rate x difference x power x test.

    Returns
    -------
    DataFrame
        Columns study, test, human_rate, robot_rate, difference, margin, alpha, target_power,
        words, trials_per_writer, icc, word_icc, sd_difference, participants, power_achieved.
    """
    m = max(words // 2, 1)
    rows = []
    for r in rates:
        for d in differences:
            rr = min(max(r + d, 1e-6), 1 - 1e-6)
            sd = paired_difference_sd(r, rr, m, icc, word_icc, words)
            for pw in powers:
                for test, fn in (
                    (
                        "paired TOST",
                        lambda n, sd=sd, d=d: paired_tost_power(n, sd, margin, d, alpha),
                    ),
                    (
                        "non-inferiority",
                        lambda n, sd=sd, d=d: noninferiority_power(n, sd, margin, d, alpha),
                    ),
                ):
                    n = _smallest(fn, pw) if (test != "paired TOST" or abs(d) < margin) else None
                    rows.append(
                        dict(
                            study="readability",
                            test=test,
                            human_rate=r,
                            robot_rate=rr,
                            difference=d,
                            margin=margin,
                            alpha=alpha,
                            target_power=pw,
                            words=words,
                            trials_per_writer=m,
                            icc=icc,
                            word_icc=word_icc,
                            sd_difference=sd,
                            participants=n if n is not None else np.nan,
                            power_achieved=fn(n) if n is not None else np.nan,
                        )
                    )
    return pd.DataFrame(rows)


def readability_power_at(
    participants: Sequence[int] = (30,),
    rate: float = 0.80,
    difference: float = 0.0,
    margin: float = 0.10,
    alpha: float = 0.05,
    words: int = 10,
    icc: float = DEFAULT_ICC,
    word_icc: float = DEFAULT_WORD_ICC,
) -> pd.DataFrame:
    """Paired-TOST and non-inferiority power for given numbers of participants (e.g. the paper's 30)."""
    m = max(words // 2, 1)
    sd = paired_difference_sd(rate, rate + difference, m, icc, word_icc, words)
    return pd.DataFrame(
        [
            dict(
                study="readability",
                participants=n,
                human_rate=rate,
                robot_rate=rate + difference,
                margin=margin,
                alpha=alpha,
                sd_difference=sd,
                power_tost=paired_tost_power(n, sd, margin, difference, alpha),
                power_noninferiority=noninferiority_power(n, sd, margin, difference, alpha),
            )
            for n in participants
        ]
    )


__all__ = [
    "TrialsNeeded",
    "binomial_tost_power",
    "binomial_tost_sample_size",
    "noninferiority_power",
    "paired_difference_sd",
    "paired_tost_power",
    "participants_needed",
    "readability_plan",
    "readability_power_at",
    "turing_plan",
    "turing_power_at",
]
