"""Tests of ``prg.pipeline.dmp.basis`` (moved from the suite on: discrete DMP (prg.pipeline.dmp):
reproduction, generalisation, exactness of the rollout, fit)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from prg.pipeline.dmp import (
    basis_count,
    basis_functions,
    fit_dmp,
)
from tests.helpers.dmp import word_like

# ----------------------------------------------------------------------------- the fit


def test_basis_functions_are_evenly_spaced_in_time_with_widths_from_the_spacing():
    centres, widths = basis_functions(50, alpha_x=3.0)
    assert_allclose(-np.log(centres) / 3.0, np.linspace(0, 1, 50), atol=1e-15)
    spacing = centres[:-1] - centres[1:]
    assert_allclose(widths[:-1], 1 / (2 * spacing**2))
    assert widths[-1] == widths[-2]


def test_basis_count_scales_with_points_and_is_clipped():
    assert basis_count(1000, per_100_points=20, minimum=5, maximum=900) == 200
    assert basis_count(10, per_100_points=20, minimum=15, maximum=900) == 15
    assert basis_count(10_000, per_100_points=20, minimum=5, maximum=300) == 300
    counts = [basis_count(n) for n in range(1, 5000, 37)]
    assert counts == sorted(counts)
    assert fit_dmp(word_like(700, loops=8)).n_basis == basis_count(700)


def test_basis_count_rejects_bad_bounds():
    with pytest.raises(ValueError, match="maximum: expected an integer >= 30"):
        basis_count(100, minimum=30, maximum=10)
    with pytest.raises(ValueError, match="per_100_points: expected a number > 0"):
        basis_count(100, per_100_points=0)


def test_basis_functions_use_a_non_default_width_factor_and_phase_constant():
    for n_basis, alpha_x, width_factor in [(7, 1.5, 2.5), (40, 5.0, 0.6)]:
        centres, widths = basis_functions(n_basis, alpha_x=alpha_x, width_factor=width_factor)
        want = np.exp(-alpha_x * np.linspace(0.0, 1.0, n_basis))
        assert_allclose(centres, want, rtol=1e-14)
        spacing = want[:-1] - want[1:]
        assert_allclose(widths, 1 / (2 * (width_factor * np.append(spacing, spacing[-1])) ** 2))
    # one basis function: the spacing 1 - exp(-alpha_x)
    centres, widths = basis_functions(1, alpha_x=2.0, width_factor=3.0)
    assert_array_equal(centres, [1.0])
    assert_allclose(widths, [1 / (2 * (3.0 * (1 - math.exp(-2.0))) ** 2)])


def test_basis_count_accepts_its_smallest_bounds_and_names_bad_ones():
    assert basis_count(1, per_100_points=10, minimum=1, maximum=1) == 1
    assert basis_count(3, per_100_points=10, minimum=1) == 1
    with pytest.raises(ValueError, match="n_points: expected an integer >= 1"):
        basis_count(0)
    with pytest.raises(ValueError, match="minimum: expected an integer >= 1"):
        basis_count(10, minimum=0)


def test_bad_basis_and_damping_values_are_named():
    with pytest.raises(ValueError, match="n_basis: expected an integer >= 1"):
        basis_functions(0)
    with pytest.raises(ValueError, match="alpha_x: expected a number > 0"):
        basis_functions(5, alpha_x=0.0)
    with pytest.raises(ValueError, match="damping: expected a finite number"):
        fit_dmp(word_like(50, loops=1), damping=np.nan)
