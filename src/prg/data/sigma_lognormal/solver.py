"""The fit's least-squares solver: projected Levenberg-Marquardt on a BLAS-free Cholesky."""

from __future__ import annotations

import math

import numpy as np

# Linear algebra of the fit without BLAS or LAPACK. Their results depend on the machine: OpenBLAS
# picks its kernels at run time by CPU (Haswell, SkylakeX, ...) and splits work over threads, each
# variant summing in its own order, and the greedy fit turns such a last-bit difference into other
# components now and then (demo set, before this: 6 failed fits of 5,208 with the SkylakeX
# kernels, 5 with OPENBLAS_CORETYPE=Haswell). numpy's einsum (optimize off) never calls BLAS and
# is not dispatched by CPU, so the fit no longer depends on the BLAS, its kernel or its threads.
# (numpy's exp, log, arctan2 and power still have AVX-512 variants: a CPU without AVX-512 gives
# slightly different fits; README, "Reproducibility".)


def _sum_squares(x: np.ndarray) -> float:
    return float(np.einsum("i,i->", x, x))


_SMALL_SOLVE = 24  # up to this size plain Python floats beat a numpy loop over columns


def _solve_spd(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve ``a x = b`` for a symmetric positive definite ``a`` by Cholesky factorisation.

    Raises ``numpy.linalg.LinAlgError`` when a pivot is not positive (``a`` not numerically
    positive definite).
    """
    if a.shape[0] <= _SMALL_SOLVE:
        return _solve_spd_small(a.tolist(), b.tolist())
    work = np.array(a, dtype=np.float64)
    x = np.array(b, dtype=np.float64)
    n = work.shape[0]
    for j in range(n):  # right-looking; the factor overwrites the lower triangle of work
        pivot = work[j, j]
        if not pivot > 0:
            raise np.linalg.LinAlgError("matrix is not positive definite")
        col = work[j:, j] / math.sqrt(pivot)
        work[j:, j] = col
        work[j + 1 :, j + 1 :] -= np.multiply.outer(col[1:], col[1:])
        x[j] /= col[0]  # forward substitution, column by column
        x[j + 1 :] -= col[1:] * x[j]
    for j in range(n - 1, -1, -1):  # back substitution with the transposed factor
        x[j] /= work[j, j]
        x[:j] -= work[j, :j] * x[j]
    return x


def _solve_spd_small(a: list[list[float]], b: list[float]) -> np.ndarray:
    # Explicit loops, not sum(): Python 3.12 changed sum() of floats to a compensated sum.
    n = len(b)
    low = [[0.0] * n for _ in range(n)]
    for j in range(n):
        row_j = low[j]
        pivot = a[j][j]
        for k in range(j):
            pivot -= row_j[k] * row_j[k]
        if not pivot > 0:
            raise np.linalg.LinAlgError("matrix is not positive definite")
        row_j[j] = diag = math.sqrt(pivot)
        for i in range(j + 1, n):
            row_i = low[i]
            v = a[i][j]
            for k in range(j):
                v -= row_i[k] * row_j[k]
            row_i[j] = v / diag
    y = list(b)
    for i in range(n):
        v = y[i]
        for k in range(i):
            v -= low[i][k] * y[k]
        y[i] = v / low[i][i]
    for i in range(n - 1, -1, -1):
        v = y[i]
        for k in range(i + 1, n):
            v -= low[k][i] * y[k]
        y[i] = v / low[i][i]
    return np.array(y)


def _levenberg_marquardt(
    evaluate, x0: np.ndarray, lo: np.ndarray, hi: np.ndarray, max_nfev: int, stop_cost: float = 0.0
) -> np.ndarray:
    """Projected Levenberg-Marquardt: Marquardt's diagonal scaling, box bounds by clipping.

    Used instead of ``scipy.optimize.least_squares`` because the latter's bounded solver takes an
    SVD per iteration that dominates the run time on these small problems (at most 90 unknowns,
    so damped normal equations, solved by Cholesky, are cheap and well enough conditioned).
    ``evaluate(x)`` returns the residual (m,) and Jacobian (m, p). Stops after ``max_nfev``
    evaluations, when the cost (sum of squares) drops to ``stop_cost`` or stalls. Never increases
    the cost; returns ``x0`` (clipped) if the residual is not finite.
    """
    x = np.clip(x0, lo, hi)
    with np.errstate(all="ignore"):
        res, jac = evaluate(x)
        cost = _sum_squares(res)
        if not np.isfinite(cost):
            return x
        lam, nfev = 1e-3, 1
        while nfev < max_nfev and cost > stop_cost:
            grad = np.einsum("ij,i->j", jac, res)
            normal = np.einsum("ij,ik->jk", jac, jac)
            diag = np.diag(normal)
            scale = np.maximum(diag, 1e-6 * diag.max() + 1e-30)  # no huge steps in idle params
            improved = False
            while nfev < max_nfev and lam < 1e8:
                try:
                    step = _solve_spd(normal + lam * np.diag(scale), -grad)
                except np.linalg.LinAlgError:
                    lam *= 10.0
                    continue
                x_new = np.clip(x + step, lo, hi)
                res_new, jac_new = evaluate(x_new)
                nfev += 1
                cost_new = _sum_squares(res_new)
                if np.isfinite(cost_new) and cost_new < cost:
                    improved = cost - cost_new > 1e-6 * cost
                    x, res, jac, cost = x_new, res_new, jac_new, cost_new
                    lam = max(lam / 3.0, 1e-9)
                    break
                lam *= 4.0
            if not improved:
                break
    return x
