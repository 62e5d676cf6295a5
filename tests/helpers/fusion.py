"""Helpers shared by the tests that were split out of tests/test_fusion.py."""

from __future__ import annotations

import torch


def _normal_pair(seed: int, shape=(7, 5)):
    g = torch.Generator().manual_seed(seed)
    mu_q, mu_p = torch.randn(shape, generator=g), torch.randn(shape, generator=g)
    lv_q, lv_p = torch.randn(shape, generator=g), torch.randn(shape, generator=g)
    return mu_q, lv_q, mu_p, lv_p
