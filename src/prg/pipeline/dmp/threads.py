"""Single-threaded BLAS for the DMP's small products and banded solves (threadpoolctl, optional)."""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Iterator
from typing import Any


@functools.cache
def _blas_controller() -> Any:
    """threadpoolctl's controller of the loaded BLAS libraries, or None without threadpoolctl."""
    try:
        from threadpoolctl import ThreadpoolController
    except ImportError:  # optional: without it BLAS keeps its default thread count
        return None
    return ThreadpoolController()


@contextlib.contextmanager
def _one_blas_thread() -> Iterator[None]:
    """Single-threaded BLAS/LAPACK for the small products and the banded Cholesky of a DMP.

    Threads gain nothing at these sizes, and OpenBLAS's threaded banded Cholesky stalls on a busy
    CPU (measured on a loaded 2-core machine, 300 basis functions: 2.2 s with 2 threads, 0.3 ms
    with one).
    """
    controller = _blas_controller()
    if controller is None:
        yield
        return
    with controller.limit(limits=1, user_api="blas"):
        yield
