"""The crossed logit model of 0/1 answers, calibrated on the probability scale.

``logit P(answer) = b0 + u_participant + v_word`` with ``u ~ N(0, su^2)``, ``v ~ N(0, sv^2)``.
Its expectations over both random effects are taken by Gauss-Hermite quadrature
(:data:`NODES`, :data:`WEIGHTS`), which gives the population-average rate and the participant
and word shares of the answers' variance (:func:`moments`), the intercept for a given rate
(:func:`intercept`) and the whole model for a rate and two shares (:func:`latent_parameters`).

Shared by the simulator (:mod:`studies.analysis.participants`), which draws answers from the model,
and the power planner (:mod:`studies.analysis.power`), which integrates over it.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize, special

_NODES, _WEIGHTS = np.polynomial.hermite.hermgauss(48)
NODES = math.sqrt(2.0) * _NODES  #: standard-normal quadrature nodes
WEIGHTS = _WEIGHTS / math.sqrt(math.pi)  #: their weights (summing to 1)
MAX_ICC = 0.5  #: largest icc + word_icc the calibration accepts


def moments(b0: float, su: float, sv: float) -> tuple[float, float, float]:
    """(mean, Var_u E[p|u], Var_v E[p|v]) of p = expit(b0 + su z1 + sv z2) by quadrature."""
    p = special.expit(b0 + su * NODES[:, None] + sv * NODES[None, :])
    mean = float(WEIGHTS @ p @ WEIGHTS)
    by_u = p @ WEIGHTS
    by_v = WEIGHTS @ p
    return mean, float(WEIGHTS @ (by_u - mean) ** 2), float(WEIGHTS @ (by_v - mean) ** 2)


def intercept(rate: float, su: float, sv: float) -> float:
    """b0 such that the population-average rate is ``rate``."""
    reach = 30.0 + 8.0 * (su + sv)  # |b0| needed grows with the random-effect SDs
    return float(optimize.brentq(lambda b: moments(b, su, sv)[0] - rate, -reach, reach, xtol=1e-12))


def latent_parameters(
    rate: float, icc: float = 0.0, word_icc: float = 0.0
) -> tuple[float, float, float]:
    """Calibrate ``(b0, su, sv)`` of the logit model to a marginal rate and two ICCs.

    Parameters
    ----------
    rate : float
        Population-average probability, in (0, 1).
    icc, word_icc : float
        Participant and word shares of the 0/1 answers' variance (probability scale), >= 0,
        together at most :data:`MAX_ICC` (0.5; larger shares need logit SDs beyond the quadrature).

    Returns
    -------
    b0, su, sv : float
        Intercept and random-effect SDs on the logit scale.
    """
    if not 0 < rate < 1:
        raise ValueError(f"rate {rate} is outside (0, 1)")
    if icc < 0 or word_icc < 0 or icc + word_icc > MAX_ICC:
        raise ValueError(
            f"icc {icc} and word_icc {word_icc} must be >= 0 with a sum of at most {MAX_ICC}"
        )
    target = rate * (1 - rate)

    def sd_for(share: float, other: float, which: int) -> float:
        if share == 0:
            return 0.0

        def f(s: float) -> float:
            su, sv = (s, other) if which == 1 else (other, s)
            return moments(intercept(rate, su, sv), su, sv)[which] - share * target

        return float(optimize.brentq(f, 1e-6, 20.0, xtol=1e-10))

    su = sd_for(icc, 0.0, 1)
    sv = sd_for(word_icc, su, 2)
    for _ in range(20):  # alternate until both shares hold together
        su_new = sd_for(icc, sv, 1)
        sv_new = sd_for(word_icc, su_new, 2)
        done = abs(su_new - su) < 1e-9 and abs(sv_new - sv) < 1e-9
        su, sv = su_new, sv_new
        if done:
            break
    return intercept(rate, su, sv), su, sv
