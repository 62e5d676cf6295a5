"""Where ``python -m prg.commands.paper_scale`` runs: ``--device`` resolved, and named for its
record (``paper_scale.json``'s ``device``)."""

from __future__ import annotations

from prg.errors import UsageError
from prg.resources import cpu_name

__all__ = ["cpu_name", "resolve_device"]


def resolve_device(device: str) -> tuple[str, str]:
    """``(accelerator, device name)``: ``cuda`` needs a GPU that torch can use."""
    import torch

    cuda = torch.cuda.is_available()
    if device == "cuda" and not cuda:
        build = "a CPU-only build" if torch.version.cuda is None else f"CUDA {torch.version.cuda}"
        raise UsageError(
            f"--device cuda: torch {torch.__version__} ({build}) sees no GPU; the paper scale "
            "is sized for one (install a CUDA build of torch there), or pass --device cpu to "
            "run it on the CPU anyway (hours: README 'Paper scale on a GPU')"
        )
    if device == "cpu" or not cuda:
        return "cpu", cpu_name()
    return "cuda", torch.cuda.get_device_name(0)
