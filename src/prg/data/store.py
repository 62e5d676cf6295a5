"""Dataset files: one uncompressed ``.npz`` per split, written byte-for-byte reproducibly.

Arrays in a split file:

- ``traj`` float32 (N, 2 * n_points): interleaved x1, y1, x2, y2, ... (normalised, y up)
- ``image`` uint8 (N, size, size): grey ink, 0..255 (the DataModule divides by 255)
- ``label`` int64 (N,): class id (``prg.alphabet``)
- ``writer`` str (N,): writer id
- ``augmented`` bool (N,): True for samples made by augmentation
- ``parent`` int64 (N,): index (in this file) of the original an augmented sample came from, -1
  for originals
"""

from __future__ import annotations

import io
import os
import zipfile
from pathlib import Path

import numpy as np

from prg.errors import UsageError
from prg.files import atomic_path

SPLIT_KEYS = ("traj", "image", "label", "writer", "augmented", "parent")
_FIXED_DATE = (1980, 1, 1, 0, 0, 0)


def save_split(path: str | os.PathLike, arrays: dict[str, np.ndarray]) -> Path:
    """Write arrays as an uncompressed npz with fixed zip metadata (same data, same bytes).

    Written to a temporary name in the same folder, then renamed.
    """
    path = Path(path)
    with (
        atomic_path(path) as tmp,
        zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_STORED, allowZip64=True) as zf,
    ):
        for key in sorted(arrays):
            buf = io.BytesIO()
            np.lib.format.write_array(buf, np.ascontiguousarray(arrays[key]), allow_pickle=False)
            info = zipfile.ZipInfo(f"{key}.npy", date_time=_FIXED_DATE)
            info.external_attr = 0o644 << 16
            zf.writestr(info, buf.getvalue())
    return path


def load_split(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """Read a split file written by :func:`save_split`.

    Raises
    ------
    UsageError
        If the file is missing, not an npz, or lacks the expected arrays.
    """
    path = Path(path)
    if not path.is_file():
        raise UsageError(f"dataset split {path} does not exist: run `prg-prepare` first")
    try:
        with np.load(path, allow_pickle=False) as npz:
            arrays = {k: npz[k] for k in npz.files}
    except (OSError, ValueError, zipfile.BadZipFile) as err:
        raise UsageError(f"dataset split {path} is not a readable npz file ({err})") from None
    missing = [k for k in SPLIT_KEYS if k not in arrays]
    if missing:
        raise UsageError(f"dataset split {path} lacks arrays {missing}: rebuild with `prg-prepare`")
    return arrays
