"""Helpers shared by the tests that were split out of tests/test_study_analysis.py."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from numpy.testing import assert_allclose


def binary_frame(k: int, n: int, participants: int = 10) -> pd.DataFrame:
    y = np.r_[np.ones(k), np.zeros(n - k)]
    rng = np.random.default_rng(0)
    rng.shuffle(y)
    return pd.DataFrame(
        {
            "participant_id": np.arange(n) % participants,
            "word": np.arange(n) // participants,
            "y": y,
        }
    )


def close(got, want, rel: float = 1e-9) -> None:
    """``got`` equals ``want`` to a relative tolerance and no absolute one: a p value of 1e-30
    must match 1e-30, not anything below pytest.approx's default absolute 1e-12."""
    assert_allclose(np.asarray(got, dtype=float), np.asarray(want, dtype=float), rtol=rel, atol=0)


def fields(row: pd.Series, *names: str) -> list[float]:
    return [float(row[n]) for n in names]


@pytest.fixture(scope="module")
def paired_frame() -> pd.DataFrame:
    """20 participants x 10 trials, half per writer, participant effects shared by both writers."""
    rng = np.random.default_rng(4)
    rows = []
    for p in range(20):
        u = rng.normal(0, 0.8)
        for w in range(10):
            writer = "human" if (w < 5) == (p % 2 == 0) else "robot"
            base = 1.2 if writer == "human" else 1.0
            rows.append(
                dict(
                    participant_id=f"P{p}",
                    word=f"w{w}",
                    writer=writer,
                    correct=float(rng.random() < 1 / (1 + np.exp(-(base + u)))),
                )
            )
    return pd.DataFrame(rows)


def two_writer_answers(participants: int, trials: int, human: float, robot: float, seed: int):
    """Every participant answers ``trials`` times per writer, right with probability ``human``
    for the human's words and ``robot`` for the robot's: a clear difference between writers."""
    rng = np.random.default_rng(seed)
    rates = {"human": human, "robot": robot}
    rows = [
        dict(participant_id=p, writer=w, correct=float(rng.random() < rates[w]))
        for p in range(participants)
        for w in ("human", "robot")
        for _ in range(trials)
    ]
    return pd.DataFrame(rows)


def gee_difference_reference(frame: pd.DataFrame, level: str):
    """statsmodels' exchangeable Gaussian GEE of ``correct`` on [1, writer == level], clustered
    by participant, with the bias-reduced sandwich: what ``gee_difference`` should report."""
    import statsmodels.api as sm

    x = (frame.writer == level).astype(float)
    return sm.GEE(
        frame["correct"],
        np.column_stack([np.ones(len(x)), x]),
        groups=pd.factorize(frame.participant_id)[0],
        family=sm.families.Gaussian(),
        cov_struct=sm.cov_struct.Exchangeable(),
    ).fit(cov_type="bias_reduced")
