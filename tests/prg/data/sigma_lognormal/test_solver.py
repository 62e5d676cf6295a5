"""Tests of ``prg.data.sigma_lognormal.solver`` (moved from the suite on: the dataset build is the
same on other machines (README, "Reproducibility").

Each build runs in its own process, so the numeric libraries start with that environment:

* bit for bit whatever the BLAS kernel (OpenBLAS picks Haswell, SkylakeX, ... by CPU;
``OPENBLAS_CORETYPE`` forces one), its thread count and ``workers``: the build uses no BLAS
where a last-bit difference could change a fit; * within the stated tolerance across SIMD
levels: numpy's exp, log, arctan2 and power have AVX-512 variants; ``NPY_DISABLE_CPU_FEATURES``
turns them off, as on a CPU without AVX-512)."""

from __future__ import annotations

import numpy as np
import pytest

from prg.data import sigma_lognormal as sl


@pytest.mark.parametrize("n", [1, 6, 24, 25, 90])  # both code paths (plain Python up to 24)
def test_the_fits_blas_free_solve_agrees_with_lapack(n):
    rng = np.random.default_rng(n)
    jac = rng.normal(size=(2 * n + 5, n))
    a = jac.T @ jac + 1e-3 * np.eye(n)
    b = rng.normal(size=n)
    x = sl._solve_spd(a, b)
    np.testing.assert_allclose(x, np.linalg.solve(a, b), rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("n", [2, 30])
def test_the_fits_blas_free_solve_refuses_an_indefinite_matrix(n):
    a = np.eye(n)
    a[-1, -1] = -1.0
    with pytest.raises(np.linalg.LinAlgError):
        sl._solve_spd(a, np.ones(n))
