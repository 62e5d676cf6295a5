"""The dataset build is the same on other machines (README, "Reproducibility").

Each build runs in its own process, so the numeric libraries start with that environment:

* bit for bit whatever the BLAS kernel (OpenBLAS picks Haswell, SkylakeX, ... by CPU;
  ``OPENBLAS_CORETYPE`` forces one), its thread count and ``workers``: the build uses no BLAS
  where a last-bit difference could change a fit;
* within the stated tolerance across SIMD levels: numpy's exp, log, arctan2 and power have
  AVX-512 variants; ``NPY_DISABLE_CPU_FEATURES`` turns them off, as on a CPU without AVX-512.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from prg.data.store import load_split
from tests.conftest import REPO

SPLITS = ("train", "val", "test")


# Builds a small synthetic dataset into argv[1]; prints checksums of a BLAS matrix product and of
# numpy's exp, which show whether the environment really changed that arithmetic.
_BUILD = """
import hashlib, json, sys
import numpy as np
from omegaconf import OmegaConf
from prg.commands.cli import compose_config
from prg.data.build import build_dataset

out, workers = sys.argv[1], int(sys.argv[2])
cfg = compose_config("prepare", [
    "data.synthetic.n_writers=6", "data.augment.per_class=4",
    "data.splits.train=0.5", "data.splits.val=0.25", "data.splits.test=0.25",
])
data = OmegaConf.to_container(cfg.data, resolve=True)
build_dataset(data, out, workers=workers, progress=False, figures=False)
a = np.random.default_rng(0).normal(size=(200, 90))
digest = lambda x: hashlib.sha256(x.tobytes()).hexdigest()
print(json.dumps({"blas": digest(a.T @ a), "exp": digest(np.exp(a))}))
"""


_NUMERIC_ENV = ("OPENBLAS_CORETYPE", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def _build(root, workers: int, **env: str) -> dict:
    base = {k: v for k, v in os.environ.items() if k not in _NUMERIC_ENV}
    base.pop("NPY_DISABLE_CPU_FEATURES", None)
    proc = subprocess.run(
        [sys.executable, "-c", _BUILD, str(root), str(workers)],
        cwd=REPO,
        env={**base, **env},
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _files(root) -> dict[str, bytes]:
    folder = root / "prepared" / "synthetic"
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def _x86_openblas_with_avx2() -> bool:
    """OpenBLAS picks its kernels at run time here, and the Haswell ones can run."""
    from numpy._core._multiarray_umath import __cpu_features__
    from threadpoolctl import threadpool_info

    openblas = any(
        i.get("internal_api") == "openblas" and i.get("architecture") for i in threadpool_info()
    )
    return openblas and bool(__cpu_features__.get("AVX2") and __cpu_features__.get("FMA3"))


def test_build_is_bit_identical_across_blas_kernels_threads_and_workers(tmp_path):
    kernels = _x86_openblas_with_avx2()  # elsewhere: threads and workers only
    a = _build(
        tmp_path / "a",
        1,
        **({"OPENBLAS_CORETYPE": "Prescott"} if kernels else {}),  # SSE3, no fused mult.-add
        OPENBLAS_NUM_THREADS="1",
        OMP_NUM_THREADS="1",
        MKL_NUM_THREADS="1",
    )
    b = _build(
        tmp_path / "b",
        2,
        **({"OPENBLAS_CORETYPE": "Haswell"} if kernels else {}),  # AVX2 + FMA
        OPENBLAS_NUM_THREADS="2",
        OMP_NUM_THREADS="2",
        MKL_NUM_THREADS="2",
    )
    if kernels:  # the two environments really do different BLAS arithmetic
        assert a["blas"] != b["blas"]
    first, second = _files(tmp_path / "a"), _files(tmp_path / "b")
    assert sorted(first) == ["manifest.json", "provenance.json", "test.npz", "train.npz", "val.npz"]
    for name in first:
        assert first[name] == second[name], name


def _dispatched_features() -> str:
    """numpy's run-time dispatched SIMD targets this CPU has (e.g. X86_V3 X86_V4 AVX512_ICL)."""
    from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__

    return " ".join(f for f in __cpu_dispatch__ if __cpu_features__.get(f))


@pytest.mark.slow
def test_build_without_simd_dispatch_is_within_the_stated_tolerance(tmp_path):
    """The tolerance across SIMD levels: same structure; originals equal to 1e-6; the failed-fit
    count within 1 + 0.1 % of the fits; 90 % of the new samples within 1e-4 of each other.

    (On a CPU whose dispatched targets compute exp like the baseline, e.g. AVX2 without AVX-512,
    both builds are the same and this holds trivially.)"""
    disabled = _dispatched_features()
    a = _build(tmp_path / "a", 2)
    b = _build(tmp_path / "b", 2, NPY_DISABLE_CPU_FEATURES=disabled)
    if any(f.startswith(("AVX512", "X86_V4")) for f in disabled.split()):  # AVX-512 exp: off
        assert a["exp"] != b["exp"]
    roots = [tmp_path / r / "prepared" / "synthetic" for r in ("a", "b")]
    manifests = [json.loads((r / "manifest.json").read_text()) for r in roots]
    aug = [m.pop("augmentation") for m in manifests]
    assert manifests[0] == manifests[1]  # splits, counts per class, config
    n_fits = aug[0]["n_fits"]
    assert abs(aug[0]["n_failed"] - aug[1]["n_failed"]) <= 1 + 0.001 * n_fits
    for split in SPLITS:
        x, y = (load_split(r / f"{split}.npz") for r in roots)
        for key in ("label", "augmented"):
            np.testing.assert_array_equal(x[key], y[key])
        originals = ~x["augmented"]
        # a new sample's parent, so its writer, differs where its class's fits differ
        np.testing.assert_array_equal(x["writer"][originals], y["writer"][originals])
        np.testing.assert_allclose(x["traj"][originals], y["traj"][originals], atol=1e-6)
        new = x["augmented"]
        if new.any():
            gap = np.abs(x["traj"][new] - y["traj"][new]).max(axis=1)
            assert np.mean(gap <= 1e-4) >= 0.9, np.sort(gap)[::-1][:10]
