"""The Perceive stage's maps: pen trajectories (phi_T) and letter images (phi_I) to model inputs.

Both maps bring user input to exactly the form of the training data, so the models see nothing new:

* :func:`perceive_trajectories` (phi_T) runs each letter's pen trajectory through
  :func:`prg.data.preprocess.preprocess_stroke` — the very function the dataset build
  (:func:`prg.data.build.preprocess_samples`) applies to raw strokes — and flattens it in the
  dataset's ``TRAJ_LAYOUT`` (interleaved ``x1, y1, x2, y2, ...``).
* :func:`perceive_letter_images` (phi_I) turns a photo/scan/drawing of one letter into a 28x28 ink
  image shaped like :func:`prg.data.preprocess.render`'s: ink bounding box centred, aspect kept,
  the stroke's centre line filling ``size - 2 * margin - stroke_width`` pixels, and the stroke
  re-thickened to the renderer's fixed width.
* :func:`segment_word_image` splits one image of a word with separated letters into letter images;
  :func:`load_image` reads an image file with Pillow.

Image normalisation, step by step (:func:`ink_intensity` then :func:`perceive_letter_image`):

1. grey level: RGB(A) to luminance (ITU-R 601 weights; RGBA is composited over white first),
   uint8 divided by 255, floats taken as ``[0, 1]`` (or ``[0, 255]`` when their maximum exceeds 1);
2. polarity from the background: the median of the border pixels is the paper colour; ink is the
   distance from it (dark ink on light paper or light ink on dark paper alike), stretched so the
   strongest ink is 1 — no threshold touches the grey levels;
3. crop to the bounding box of the pixels with ink >= ``NOISE_LEVEL``, ignoring specks (connected
   components smaller than ``max(2 px, 0.5 %)`` of the ink area);
4. stroke width ``w`` estimated from the ink area ``A`` and the perimeter ``P`` of the ink mask
   (a stroke of length ``L`` and width ``w`` has ``A = w L`` and ``P = 2 (L + w)``, so
   ``w = (P/2 - sqrt(P^2/4 - 4A)) / 2``; ``P`` counts mask edges times pi/4 for digitisation);
5. scale (Pillow LANCZOS, aspect kept) so the centre line's extent ``max(h, w_box) - w`` spans the
   renderer's usable width, centred, on a canvas ``_OVERSAMPLE`` times the final size;
6. thickness: grey dilation (or erosion) with a disc so the stroke width becomes the renderer's
   ``stroke_width`` (times the oversampling);
7. area-average down to ``size x size``; values clipped to ``[0, 1]``, float32.
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from prg.data.preprocess import TRAJ_LAYOUT, preprocess_stroke
from prg.errors import UsageError
from prg.files import read_json

IMAGE_SIZE = 28  # as conf/data/_base_.yaml data.image
STROKE_WIDTH = 2.0
MARGIN = 2.0
NOISE_LEVEL = 0.15  # ink below this (fraction of the strongest ink) does not count for the crop
BLANK_CONTRAST = 0.08  # an image whose strongest ink differs less than this from paper is blank
_OVERSAMPLE = 4  # working resolution = _OVERSAMPLE * size, area-averaged down at the end
_SEGMENT_LEVEL = 0.35  # ink level at which word images are binarised for segmentation

assert TRAJ_LAYOUT == "interleaved"  # perceive_trajectories flattens with reshape(-1)


# --------------------------------------------------------------------------------------------
# phi_T: trajectories
# --------------------------------------------------------------------------------------------


def perceive_trajectories(
    strokes: Sequence[np.ndarray],
    y_down: bool = False,
    n_points: int = 100,
    smooth_sigma: float = 1.0,
) -> np.ndarray:
    """phi_T: per-letter pen trajectories to the dataset's normalised trajectory vectors.

    Parameters
    ----------
    strokes : sequence of ndarray, each shape (n_i, 2)
        One pen-down trajectory per letter, any number of points (>= 2), any scale and offset.
    y_down : bool
        True when the y axis points down (tablet, screen or image coordinates); the dataset build
        uses ``True`` for its raw UJI/Hershey strokes.
    n_points, smooth_sigma : int, float
        As the dataset's ``data.preprocess`` (defaults: the paper's 100 points, sigma 1).

    Returns
    -------
    ndarray, shape (N, 2 * n_points), float32
        Interleaved ``x1, y1, x2, y2, ...`` (``TRAJ_LAYOUT``), y up, centred, max ``|coord|`` = 1.

    Raises
    ------
    UsageError
        Naming the letter index: not (n, 2), fewer than 2 points, NaN/inf, zero length.
    """
    if isinstance(strokes, np.ndarray) and strokes.ndim == 2:
        raise UsageError(
            "strokes must be a sequence of (n, 2) arrays, one per letter; got one array"
        )
    if len(strokes) == 0:
        raise UsageError("strokes is empty: give one (n, 2) trajectory per letter")
    out = []
    for i, stroke in enumerate(strokes):
        try:
            arr = np.asarray(stroke, dtype=np.float64)
        except (TypeError, ValueError) as err:
            raise UsageError(f"letter {i}: trajectory is not numeric ({err})") from None
        if arr.ndim != 2 or arr.shape[1] != 2:
            raise UsageError(f"letter {i}: trajectory must have shape (n, 2), got {arr.shape}")
        if arr.shape[0] < 2:
            raise UsageError(f"letter {i}: trajectory needs at least 2 points, got {arr.shape[0]}")
        if not np.all(np.isfinite(arr)):
            raise UsageError(f"letter {i}: trajectory contains NaN or infinite values")
        if not np.any(np.abs(np.diff(arr, axis=0)) > 0):
            raise UsageError(f"letter {i}: trajectory has zero length (all points identical)")
        try:
            pts = preprocess_stroke(arr, n_points, smooth_sigma, y_down=y_down)
        except UsageError as err:
            raise UsageError(f"letter {i}: {err}") from None
        out.append(pts.reshape(-1))
    return np.stack(out).astype(np.float32)


# --------------------------------------------------------------------------------------------
# phi_I: images
# --------------------------------------------------------------------------------------------


def load_image(path: str | os.PathLike) -> np.ndarray:
    """Read an image file with Pillow.

    Returns
    -------
    ndarray
        ``(H, W)`` uint8 for grey images, ``(H, W, 3)`` uint8 for colour, ``(H, W, 4)`` uint8
        when the file has transparency, ``(H, W)`` float32 in ``[0, 1]`` for 16/32-bit images.

    Raises
    ------
    UsageError
        One line naming the file when it is missing, unreadable or not an image.
    """
    from PIL import Image, UnidentifiedImageError

    try:
        with warnings.catch_warnings():  # Pillow only warns below twice its pixel limit
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            img = Image.open(path)
        with img:
            img.load()
            mode = img.mode
            if mode in ("I", "I;16", "I;16B", "I;16L", "F"):
                arr = np.asarray(img, dtype=np.float64)
                top = arr.max()
                return (arr / top if top > 1 else arr).astype(np.float32)
            has_alpha = "A" in mode or "transparency" in img.info
            if has_alpha:
                return np.asarray(img.convert("RGBA"))
            if mode in ("1", "L"):
                return np.asarray(img.convert("L"))
            return np.asarray(img.convert("RGB"))
    except FileNotFoundError:
        raise UsageError(f"{path}: no such image file") from None
    except UnidentifiedImageError:
        raise UsageError(f"{path}: not an image Pillow can read") from None
    except (Image.DecompressionBombError, Image.DecompressionBombWarning) as err:
        size = str(err).split(",")[0]  # "Image size (N pixels) exceeds limit of M pixels"
        raise UsageError(f"{path}: image too large to read: {size}") from None
    except (OSError, ValueError) as err:
        raise UsageError(f"{path}: cannot read image ({err})") from None


def _grey(image: np.ndarray, name: str) -> np.ndarray:
    """Grey level in [0, 1] of a grey/RGB/RGBA image, uint8 or float."""
    arr = np.asarray(image)
    if arr.dtype == bool:
        arr = arr.astype(np.float64)
    if not (np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
        raise UsageError(f"{name}: image must be numeric, got dtype {arr.dtype}")
    if arr.ndim == 3 and arr.shape[2] == 1:
        arr = arr[..., 0]
    if not (arr.ndim == 2 or (arr.ndim == 3 and arr.shape[2] in (3, 4))):
        raise UsageError(f"{name}: image must be (H, W), (H, W, 3) or (H, W, 4), got {arr.shape}")
    if arr.shape[0] < 2 or arr.shape[1] < 2:
        raise UsageError(f"{name}: image is too small ({arr.shape[0]}x{arr.shape[1]} pixels)")
    if np.issubdtype(arr.dtype, np.integer):
        top = 255.0 if arr.dtype.itemsize == 1 or arr.max() <= 255 else 65535.0
        x = arr.astype(np.float64) / top
    else:
        x = arr.astype(np.float64)
        if not np.all(np.isfinite(x)):
            raise UsageError(f"{name}: image contains NaN or infinite values")
        if x.max() > 1.0 + 1e-6:
            x = x / 255.0
    x = np.clip(x, 0.0, 1.0)
    if x.ndim == 3:
        if x.shape[2] == 4:  # composite over white paper
            alpha = x[..., 3:]
            x = x[..., :3] * alpha + (1.0 - alpha)
        x = x @ np.array([0.299, 0.587, 0.114])
    return x


def ink_intensity(image: np.ndarray, name: str = "image") -> np.ndarray:
    """Ink intensity (ink = 1, paper = 0) of an image, polarity detected from its border.

    Parameters
    ----------
    image : ndarray, shape (H, W), (H, W, 3) or (H, W, 4)
        uint8 or float; dark ink on light paper or light ink on dark paper.
    name : str
        How to name the image in error messages.

    Returns
    -------
    ndarray, shape (H, W), float64 in [0, 1]

    Raises
    ------
    UsageError
        If the image is malformed or blank (no ink differs from the paper by ``BLANK_CONTRAST``).
    """
    grey = _grey(image, name)
    border = np.concatenate([grey[0], grey[-1], grey[1:-1, 0], grey[1:-1, -1]])
    paper = float(np.median(border))
    ink = paper - grey if paper >= 0.5 else grey - paper
    strongest = float(ink.max())
    if strongest < BLANK_CONTRAST:
        raise UsageError(f"{name}: image is blank (no ink stands out from the background)")
    return np.clip(ink / strongest, 0.0, 1.0)


def _ink_mask(ink: np.ndarray, level: float) -> np.ndarray:
    """Pixels at or above ``level``, without specks (components < max(2 px, 0.5 % of the ink))."""
    from scipy import ndimage  # here: writing from text never needs it

    mask = ink >= level
    labels, n = ndimage.label(mask, structure=np.ones((3, 3)))
    if n > 1:
        sizes = np.bincount(labels.ravel())[1:]
        keep = sizes >= max(2, 0.005 * sizes.sum())
        if keep.any():
            mask = keep[labels - 1] & mask
    return mask


def estimate_stroke_width(ink: np.ndarray) -> float:
    """Stroke width in pixels of an ink image, from ink area and the ink mask's perimeter.

    A stroke of length ``L`` and width ``w`` has area ``A = w L`` and perimeter ``P = 2 (L + w)``,
    whence ``w = (P/2 - sqrt(P^2/4 - 4 A)) / 2``. ``A`` is the summed (soft) ink, ``P`` the number
    of mask/background pixel edges of the mask ``ink >= 0.5`` times pi/4 (a digitised curve's
    edge count overestimates its length by 4/pi on average).

    Parameters
    ----------
    ink : ndarray, shape (H, W)
        Ink intensity in [0, 1].

    Returns
    -------
    float
        At least 1 pixel.
    """
    mask = np.pad(ink >= 0.5, 1)
    edges = np.count_nonzero(mask[1:] != mask[:-1]) + np.count_nonzero(mask[:, 1:] != mask[:, :-1])
    perimeter = edges * math.pi / 4
    area = float(ink.sum())
    half = perimeter / 2
    disc = half * half - 4 * area
    width = (half - math.sqrt(disc)) / 2 if disc > 0 else half / 2  # blob: w = L
    return max(width, 1.0)


def _disc(radius: int) -> np.ndarray:
    r = np.arange(-radius, radius + 1)
    return (r[:, None] ** 2 + r[None, :] ** 2) <= radius * radius + 0.5


def perceive_letter_image(
    image: np.ndarray,
    size: int = IMAGE_SIZE,
    stroke_width: float | None = STROKE_WIDTH,
    margin: float = MARGIN,
    name: str = "image",
) -> np.ndarray:
    """phi_I for one letter image; see :func:`perceive_letter_images` and the module docstring.

    Parameters
    ----------
    image : ndarray, shape (H, W), (H, W, 3) or (H, W, 4)
    size, stroke_width, margin
        As the dataset's ``data.image`` (:func:`prg.data.preprocess.render`). ``stroke_width=None``
        keeps the input's own stroke thickness (scaled with the letter).
    name : str
        How to name the image in error messages.

    Returns
    -------
    ndarray, shape (size, size), float32 in [0, 1]
    """
    from PIL import Image
    from scipy import ndimage  # here: writing from text never needs it

    ink = ink_intensity(image, name)
    mask = _ink_mask(ink, NOISE_LEVEL)
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    box = (slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1))
    crop = np.where((ink >= NOISE_LEVEL) & ~mask, 0.0, ink)[box]  # specks go
    h, w = crop.shape
    k = _OVERSAMPLE
    canvas_side = size * k
    width_in = min(estimate_stroke_width(crop), 0.5 * max(h, w))
    if stroke_width is None:  # keep thickness: the ink box fills size - 2 margin
        scale = k * (size - 2 * margin) / max(h, w)
    else:
        usable = size - 2 * margin - stroke_width
        scale = k * usable / max(max(h, w) - width_in, 1.0)
    new_w, new_h = max(1, round(w * scale)), max(1, round(h * scale))
    if new_w > canvas_side or new_h > canvas_side:  # thick strokes: never leave the canvas
        shrink = canvas_side / max(new_w, new_h)
        scale *= shrink
        new_w, new_h = max(1, round(w * scale)), max(1, round(h * scale))
    pil = Image.fromarray(crop.astype(np.float32), mode="F")
    resized = np.asarray(pil.resize((new_w, new_h), Image.Resampling.LANCZOS), dtype=np.float64)
    canvas = np.zeros((canvas_side, canvas_side))
    top, left = (canvas_side - new_h) // 2, (canvas_side - new_w) // 2
    canvas[top : top + new_h, left : left + new_w] = np.clip(resized, 0.0, 1.0)
    if stroke_width is not None:
        change = (k * stroke_width - width_in * scale) / 2  # radius to add (+) or remove (-)
        radius = round(abs(change))
        if radius > 0:
            op = ndimage.grey_dilation if change > 0 else ndimage.grey_erosion
            canvas = op(canvas, footprint=_disc(radius))
    small = canvas.reshape(size, k, size, k).mean(axis=(1, 3))
    return np.clip(small, 0.0, 1.0).astype(np.float32)


def perceive_letter_images(
    images: Sequence[np.ndarray],
    size: int = IMAGE_SIZE,
    stroke_width: float | None = STROKE_WIDTH,
    margin: float = MARGIN,
) -> np.ndarray:
    """phi_I: per-letter images to the dataset's image modality.

    Parameters
    ----------
    images : sequence of ndarray, each (H, W), (H, W, 3) or (H, W, 4)
        One image per letter, any size, uint8 or float, dark-on-light or light-on-dark.
    size, stroke_width, margin
        As the dataset's ``data.image`` (defaults 28, 2, 2).

    Returns
    -------
    ndarray, shape (N, 1, size, size), float32 in [0, 1]
        Ink = 1, like the dataset's ``image / 255``.

    Raises
    ------
    UsageError
        Naming the letter index: malformed or blank image.
    """
    if isinstance(images, np.ndarray) and images.ndim == 2:
        raise UsageError("images must be a sequence of images, one per letter; got one image")
    if len(images) == 0:
        raise UsageError("images is empty: give one image per letter")
    out = [
        perceive_letter_image(img, size, stroke_width, margin, name=f"letter {i}")
        for i, img in enumerate(images)
    ]
    return np.stack(out)[:, None]


def segment_word_image(
    image: np.ndarray, min_gap: int = 1, name: str = "word image"
) -> list[np.ndarray]:
    """Split an image of a word whose letters do not touch into per-letter images, left to right.

    The ink (:func:`ink_intensity`) is binarised at ``_SEGMENT_LEVEL``; its 8-connected
    components (specks dropped) are grouped by their column spans: components whose spans overlap
    or lie closer than ``min_gap`` columns (a letter's dot, a broken stroke above another) form one
    letter. Each letter is cut from the input over its columns, widened by half the gap to its
    neighbours, over the full height, so its border is paper and :func:`perceive_letter_images`
    can take it as it is.

    Parameters
    ----------
    image : ndarray, shape (H, W), (H, W, 3) or (H, W, 4)
    min_gap : int
        Spans separated by fewer empty columns than this are merged.
    name : str
        The image in error messages (its file).

    Returns
    -------
    list of ndarray
        Crops of ``image`` (same dtype and channels), one per letter.

    Raises
    ------
    UsageError
        If the image is malformed or blank.
    """
    from scipy import ndimage  # here: writing from text never needs it

    ink = ink_intensity(image, name)
    mask = _ink_mask(ink, _SEGMENT_LEVEL)
    labels, _ = ndimage.label(mask, structure=np.ones((3, 3)))
    spans = []
    for sl in ndimage.find_objects(labels):
        if sl is not None:
            spans.append([sl[1].start, sl[1].stop])  # columns [start, stop)
    if not spans:
        raise UsageError(f"{name}: image is blank (no ink stands out from the background)")
    spans.sort()
    merged = [spans[0]]
    for start, stop in spans[1:]:
        if start < merged[-1][1] + min_gap:
            merged[-1][1] = max(merged[-1][1], stop)
        else:
            merged.append([start, stop])
    arr = np.asarray(image)
    width = arr.shape[1]
    crops = []
    for j, (start, stop) in enumerate(merged):
        lo = 0 if j == 0 else (merged[j - 1][1] + start) // 2
        hi = width if j == len(merged) - 1 else (stop + merged[j + 1][0] + 1) // 2
        crops.append(arr[:, lo:hi].copy())
    return crops


# --------------------------------------------------------------------------------------------
# the channels' files
# --------------------------------------------------------------------------------------------

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")


def read_letter_images(path: str | os.PathLike) -> list[np.ndarray]:
    """The letters' images from an image of a word (segmented into letters, which must not
    touch) or from a folder of letter images (one per letter, in the order of their names)."""
    path = Path(path)
    if path.is_dir():
        files = sorted(p for p in path.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
        if not files:
            raise UsageError(f"images folder {path} holds no {'/'.join(IMAGE_SUFFIXES)} files")
        return [load_image(f) for f in files]
    return segment_word_image(load_image(path), name=f"images={path}")


def read_trajectories(path: str | os.PathLike) -> tuple[list[np.ndarray], bool]:
    """The letters' pen strokes and whether their y axis points down, from a JSON file:
    ``{"strokes": [[[x, y], ...], ...], "y_down": false}`` (one pen-down stroke per letter, any
    scale) or a bare list of strokes (y up)."""
    path = Path(path)
    doc = read_json(path, "trajectories file")
    strokes, y_down = (doc, False) if isinstance(doc, list) else (None, False)
    if isinstance(doc, dict):
        strokes, y_down = doc.get("strokes"), bool(doc.get("y_down", False))
    if not isinstance(strokes, list) or not strokes:
        raise UsageError(
            f"trajectories file {path}: expected a non-empty list of strokes, each a list of "
            '[x, y] points (or {"strokes": [...], "y_down": bool})'
        )
    try:
        arrays = [np.asarray(stroke, dtype=np.float64) for stroke in strokes]
    except (TypeError, ValueError):
        raise UsageError(f"trajectories file {path}: strokes must hold [x, y] numbers") from None
    return arrays, y_down
