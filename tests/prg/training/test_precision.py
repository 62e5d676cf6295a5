"""Tests of ``prg.training.precision``: bf16 autocast kept where it is fast, fp32 on a CPU without
bf16 kernels (a real process with oneDNN held to AVX2), other precisions untouched."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from prg.training.precision import usable_precision


@pytest.mark.parametrize(
    "requested, on_gpu, bf16, expected",
    [
        ("bf16-mixed", False, True, "bf16-mixed"),
        ("bf16-mixed", False, False, "32-true"),
        ("bf16-mixed", True, False, "bf16-mixed"),
        ("32-true", False, False, "32-true"),
        ("16-mixed", False, False, "16-mixed"),
    ],
)
def test_only_bf16_on_a_cpu_without_bf16_kernels_falls_back(requested, on_gpu, bf16, expected):
    assert usable_precision(requested, on_gpu, bf16) == expected


def test_a_cpu_held_to_avx2_has_no_bf16_kernels():
    code = "from prg.training.precision import cpu_has_bf16; print(cpu_has_bf16())"
    env = {**os.environ, "ONEDNN_MAX_CPU_ISA": "AVX2", "MKL_ENABLE_INSTRUCTIONS": "AVX2"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert out.stdout.strip() == "False", out.stderr
