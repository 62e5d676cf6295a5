"""Headless figures: matplotlib's pyplot on the Agg backend, for every figure the project saves."""

from __future__ import annotations


def pyplot():
    """matplotlib's pyplot on the non-interactive Agg backend (headless, no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt
