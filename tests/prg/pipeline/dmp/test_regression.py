"""Tests of ``prg.pipeline.dmp.regression`` (moved from the suite on: discrete DMP
(prg.pipeline.dmp): reproduction, generalisation, exactness of the rollout, fit)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, target
from hypothesis import strategies as st
from numpy.testing import assert_array_equal

from prg.errors import UsageError
from prg.pipeline.dmp import (
    fit_dmp,
    rollout,
)
from tests.helpers.dmp import moving_curve, rmse, word, word_dmp, word_like  # noqa: F401 (fixtures)
from tests.helpers.properties import (
    DEVIATION,
    END_ERROR,
    STEP_RATIO,
    demonstrations,
    examples,
    log_uniform,
    steps,
    walked,
)


def test_dmp_arrays_are_read_only(word_dmp):
    with pytest.raises(ValueError, match="read-only"):
        word_dmp.weights[0, 0] = 1.0


# ----------------------------------------------------------------------------- bad inputs


@pytest.mark.parametrize(
    ("points", "kwargs", "match"),
    [
        ([[0, 0], [1, np.nan], [2, 0]], {}, "points: expected finite"),
        ([[0, 0], [1, np.inf], [2, 0]], {}, "points: expected finite"),
        ([[0, 0], [1, 1]], {}, r"points: .*n >= 3"),
        ([0.0, 1.0, 2.0], {}, "points: expected a 2-D array"),
        (np.zeros((4, 2, 2)), {}, "points: expected a 2-D array"),
        (np.zeros((5, 0)), {}, r"points: .*dims >= 1"),
        ([["a", "b"], ["c", "d"], ["e", "f"]], {}, "points: expected an array of numbers"),
        (np.zeros((5, 2)), {"n_basis": 0}, "n_basis: expected an integer >= 1"),
        (np.zeros((5, 2)), {"n_basis": 2.5}, "n_basis: expected an integer >= 1"),
        (np.zeros((5, 2)), {"tau": 0.0}, "tau: expected a number > 0"),
        (np.zeros((5, 2)), {"tau": -1.0}, "tau: expected a number > 0"),
        (np.zeros((5, 2)), {"tau": np.nan}, "tau: expected a finite number"),
        (np.zeros((5, 2)), {"regularisation": -1e-3}, "regularisation: expected a number >= 0"),
    ],
)
def test_bad_fit_inputs_raise_value_error_naming_the_argument(points, kwargs, match):
    with pytest.raises(ValueError, match=match) as info:
        fit_dmp(points, **kwargs)
    assert isinstance(info.value, UsageError)


def test_every_array_of_a_new_dmp_is_read_only():
    dmp = fit_dmp(word_like(60, loops=1), n_basis=5)
    for name in ("weights", "y0", "goal", "centres", "widths"):
        arr = getattr(dmp, name)
        assert arr.dtype == np.float64
        with pytest.raises(ValueError, match="read-only"):
            arr[0] = 1.0


def test_rest_is_the_default_and_keeps_both_ends_at_rest(word):
    dmp = fit_dmp(moving_curve(), tau=2.0, n_basis=80)
    assert_array_equal(dmp.start_velocity, 0)
    assert_array_equal(dmp.goal_velocity, 0)
    out = rollout(dmp, 2001)
    step = 2.0 / 2000
    # starts at rest, unlike the path (9.7 cm/s): the first step only accelerates
    assert np.linalg.norm(out[1] - out[0]) / step < 0.01 * (4.0 + 0.6 * 3 * np.pi)
    # fitted at rest or with velocities, a word that starts and ends at rest is reproduced alike
    at_rest = rollout(fit_dmp(word, tau=3.0))
    demonstrated = rollout(fit_dmp(word, tau=3.0, velocities="demonstrated"))
    assert rmse(at_rest, demonstrated) < 1e-4


def test_bad_velocities_name_the_argument_and_what_is_accepted():
    with pytest.raises(UsageError, match="velocities: expected one of rest, demonstrated"):
        fit_dmp(moving_curve(100), velocities="measured")
    dmp = fit_dmp(moving_curve(100), n_basis=20)
    with pytest.raises(UsageError, match="goal_velocity: expected finite values"):
        rollout(dmp, goal_velocity=[np.nan, 0.0])


_LOOPS = np.column_stack([np.cos(np.linspace(0, 40, 200)), np.sin(np.linspace(0, 40, 200))])


LONG = walked(_LOOPS * [10.0, 1.0], 5000)  # 5000 samples, 2000 basis functions


NEARLY_CONSTANT = walked(1e4 + 1e-9 * _LOOPS[:50], 400)  # 1e-9 cm of motion around 1e4 cm


@examples(80)
@given(demo=demonstrations(), tau=log_uniform(-2, 2))
@example(demo=LONG, tau=30.0)
@example(demo=NEARLY_CONSTANT, tau=1.0)  # was 70 steps off: targets rounded at the offset
def test_dmp_reproduces_any_demonstration_without_jumps(demo, tau):
    dmp = fit_dmp(demo, tau=tau)
    assert np.all(np.isfinite(dmp.weights))
    out = rollout(dmp)
    assert out.shape == demo.shape and np.all(np.isfinite(out))
    np.testing.assert_array_equal(out[0], demo[0])
    largest = steps(demo).max()
    tol = 16 * np.spacing(np.abs(demo).max())  # the coordinates' own rounding
    target(float(steps(out).max() / largest), label="step ratio")
    target(float(np.hypot(*(out[-1] - demo[-1])) / largest), label="end error")
    target(float(np.hypot(*(out - demo).T).max() / largest), label="deviation")
    assert steps(out).max() <= STEP_RATIO * largest + tol
    assert np.hypot(*(out[-1] - demo[-1])) <= END_ERROR * largest + tol
    assert np.hypot(*(out - demo).T).max() <= DEVIATION * largest + tol


@examples(40)
@given(demo=demonstrations(), power=st.integers(2, 40), sign=st.sampled_from([-1.0, 1.0]))
@example(demo=walked(np.array([[0.0, 0.0], [0.0, 0.25]]), 5), power=2, sign=-1.0)  # was a bug
def test_the_dmp_depends_on_the_demonstration_only_through_differences(demo, power, sign):
    """Shifting a demonstration far away (by a power of two, so that shifting back is exact)
    gives the same weights and the same rollout, shifted (up to rounding of the final sum)."""
    shift = sign * 2.0 ** (power + math.ceil(math.log2(np.abs(demo).max() + 1e-300)))
    far = demo + shift
    near = far - shift  # exact: far and shift are within a factor of two
    a, b = fit_dmp(near), fit_dmp(far)
    np.testing.assert_allclose(b.weights, a.weights, rtol=0, atol=1e-12 * np.abs(a.weights).max())
    ulp = np.spacing(abs(shift))
    np.testing.assert_allclose(rollout(b), rollout(a) + shift, rtol=0, atol=4 * ulp)
