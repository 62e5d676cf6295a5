"""The training precision a machine can run fast: bf16 autocast only where there are bf16 kernels.

The fast recipe trains in ``bf16-mixed`` (1.5-2x the fp32 throughput on a CPU with AVX-512 bf16).
On a CPU whose oneDNN has no bf16 kernels (AVX2 and older), autocast emulates bf16 and the same
training is many times slower than in fp32 (docs/training.md, "Reproducibility of a training"),
so there ``bf16-mixed`` becomes ``32-true``. A GPU keeps what was asked.
"""

from __future__ import annotations

BF16 = "bf16-mixed"
FP32 = "32-true"


def usable_precision(requested: str, on_gpu: bool, cpu_has_bf16: bool) -> str:
    """``requested``, or ``32-true`` where it is ``bf16-mixed`` on a CPU without bf16 kernels."""
    if str(requested) == BF16 and not on_gpu and not cpu_has_bf16:
        return FP32
    return str(requested)


def trains_on_gpu(accelerator: str) -> bool:
    """Whether Lightning's ``accelerator`` setting puts training on a CUDA GPU here."""
    import torch

    name = str(accelerator).lower()
    return name in ("gpu", "cuda") or (name == "auto" and torch.cuda.is_available())


def cpu_has_bf16() -> bool:
    """Whether this CPU's oneDNN has bf16 kernels (AVX-512 bf16, AMX), as torch reports it."""
    import torch

    return bool(torch.ops.mkldnn._is_mkldnn_bf16_supported())
