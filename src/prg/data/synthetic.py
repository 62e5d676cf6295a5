"""Offline synthetic substitute for UJI Pen Characters v2, built from single-line Hershey fonts.

The UJI file cannot be fetched on an offline machine, so the default dataset is generated. It
mirrors UJI's shape: ``n_writers`` writers (60 by default) x ``samples_per_char`` sessions
(2 by default) x 62 characters, every sample a single pen-down stroke in y-down coordinates,
so writer-disjoint splits mean what they mean for UJI. It then goes through the same
preprocessing and augmentation as UJI and is labelled ``synthetic`` everywhere.

A writer is a font (``futural``, ``rowmans``, ``scripts``, ``cursive``, assigned in turn) plus a
personal style drawn once: slant (shear), width, size, rotation, roundness (corner smoothing) and
the amplitude of a smooth jitter. Each sample draws small variations around that style and its own
jitter, so the two samples of a writer differ like two sessions of one person.

**Multi-stroke glyphs become one stroke** (what UJI writers do when they write a letter without
lifting the pen), by :func:`join_strokes`: dots (strokes smaller than a tenth of the glyph) are
left out, as one-stroke writers of ``i`` and ``j`` do; the remaining strokes are ordered two ways —
the font's order, and a greedy order that starts at the top-left-most stroke end and always goes on
to the nearest free stroke end — each stroke reversed when that brings its start nearer to the pen;
the order with the shorter total pen travel between strokes wins, and consecutive strokes are
joined by a straight pen-down segment.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, field
from functools import lru_cache

import numpy as np
from scipy.ndimage import gaussian_filter1d

from prg.alphabet import ALPHABET
from prg.data.preprocess import resample_arclength
from prg.data.samples import RawSample
from prg.errors import SettingsError, UsageError
from prg.fields import check_fields, checked, integer

FONTS: tuple[str, ...] = ("futural", "rowmans", "scripts", "cursive")


@dataclass(frozen=True)
class SyntheticSettings:
    """Settings of the synthetic source (``data.synthetic`` in the Hydra config).

    A refused value raises :class:`~prg.errors.SettingsError` naming its field; ranges whose ends
    are out of order or sign raise :class:`~prg.errors.UsageError` naming the fields.
    """

    n_writers: int = checked(60, integer)
    samples_per_char: int = checked(2, integer)
    fonts: tuple[str, ...] = FONTS
    seed: int = 0
    slant: tuple[float, float] = (-0.35, 0.25)  # shear dx = slant * height, writer range
    width: tuple[float, float] = (0.75, 1.25)  # horizontal scale, writer range
    size: tuple[float, float] = (0.8, 1.25)  # overall scale, writer range
    rotation_deg: tuple[float, float] = (-6.0, 6.0)
    roundness: tuple[float, float] = (0.5, 4.0)  # corner smoothing (sigma, in font units)
    jitter: tuple[float, float] = (0.01, 0.035)  # smooth jitter amplitude / glyph height
    sample_variation: float = 0.06  # per-sample spread around the writer's slant/width/rotation
    characters: str = ALPHABET
    points_per_unit: float = 2.0  # raw sampling density along the stroke (points per font unit)

    def __post_init__(self):
        check_fields(self)
        unknown = [f for f in self.fonts if f not in FONTS]
        if unknown or not self.fonts:
            raise SettingsError("fonts", f"has {unknown or 'nothing'}: accepted are {list(FONTS)}")
        for name in ("slant", "width", "size", "rotation_deg", "roundness", "jitter"):
            pair = getattr(self, name)
            if len(pair) != 2 or not all(isinstance(v, int | float) for v in pair):
                raise SettingsError(name, f"must be [min, max] numbers, got {pair!r}")
            lo, hi = pair
            if lo > hi:
                raise SettingsError(name, f"range [{lo}, {hi}] has min > max")
        if self.width[0] <= 0 or self.size[0] <= 0 or self.roundness[0] < 0 or self.jitter[0] < 0:
            raise UsageError("width and size must be > 0, roundness/jitter >= 0")

    def fingerprint(self) -> str:
        """SHA-256 of the settings and the font package version: the synthetic 'input checksum'."""
        from importlib.metadata import version

        payload = json.dumps(
            {"config": asdict(self), "hershey-fonts": version("hershey-fonts")}, sort_keys=True
        )
        return hashlib.sha256(payload.encode()).hexdigest()


@dataclass(frozen=True)
class WriterStyle:
    font: str
    slant: float
    width: float
    size: float
    rotation_deg: float
    roundness: float
    jitter: float
    extras: dict = field(default_factory=dict)


@lru_cache(maxsize=len(FONTS))
def _font_glyphs(font: str) -> dict[str, list[np.ndarray]]:
    from HersheyFonts import HersheyFonts

    typeface = HersheyFonts()
    typeface.load_default_font(font)
    glyphs = {}
    for ch in ALPHABET:
        strokes = [np.asarray(s, dtype=np.float64) for s in typeface.strokes_for_text(ch)]
        glyphs[ch] = [s for s in strokes if len(s) >= 1]
    return glyphs


def join_strokes(strokes: list[np.ndarray], dot_fraction: float = 0.1) -> np.ndarray:
    """Join a glyph's strokes into one pen-down polyline (the rule in the module docstring).

    Parameters
    ----------
    strokes : list of ndarray, each shape (k, 2)
        The glyph's strokes, y down.
    dot_fraction : float
        Strokes whose extent is below this fraction of the glyph's extent count as dots.

    Returns
    -------
    ndarray, shape (m, 2)
    """
    if not strokes:
        raise UsageError("glyph has no strokes")
    glyph_extent = np.ptp(np.concatenate(strokes), axis=0).max()
    kept = [s for s in strokes if np.ptp(s, axis=0).max() >= dot_fraction * glyph_extent]
    kept = kept or strokes
    candidates = [_chain(kept), _chain(_greedy_order(kept))]
    travel = [t for _, t in candidates]
    return candidates[int(np.argmin(travel))][0]


def _chain(strokes: list[np.ndarray]) -> tuple[np.ndarray, float]:
    """Concatenate strokes in the given order, reversing each when its end is nearer the pen."""
    path, travel = [strokes[0]], 0.0
    for stroke in strokes[1:]:
        pen = path[-1][-1]
        if np.linalg.norm(stroke[-1] - pen) < np.linalg.norm(stroke[0] - pen):
            stroke = stroke[::-1]
        travel += float(np.linalg.norm(stroke[0] - pen))
        path.append(stroke)
    return np.concatenate(path, axis=0), travel


def _greedy_order(strokes: list[np.ndarray]) -> list[np.ndarray]:
    """Start at the top-left-most stroke end, then always the stroke with the nearest end."""
    ends = [(i, rev) for i in range(len(strokes)) for rev in (False, True)]

    def start_of(i: int, rev: bool) -> np.ndarray:
        return strokes[i][-1] if rev else strokes[i][0]

    first = min(ends, key=lambda e: start_of(*e)[0] + start_of(*e)[1])  # y down: small = top
    order, used = [strokes[first[0]][::-1] if first[1] else strokes[first[0]]], {first[0]}
    while len(used) < len(strokes):
        pen = order[-1][-1]
        i, rev = min(
            (e for e in ends if e[0] not in used),
            key=lambda e: np.linalg.norm(start_of(*e) - pen),
        )
        order.append(strokes[i][::-1] if rev else strokes[i])
        used.add(i)
    return order


def writer_styles(cfg: SyntheticSettings) -> list[WriterStyle]:
    """One style per writer, deterministic for ``cfg.seed``."""
    rng = np.random.default_rng(np.random.SeedSequence([cfg.seed, 0x57]))
    styles = []
    for w in range(cfg.n_writers):
        styles.append(
            WriterStyle(
                font=cfg.fonts[w % len(cfg.fonts)],
                slant=rng.uniform(*cfg.slant),
                width=rng.uniform(*cfg.width),
                size=rng.uniform(*cfg.size),
                rotation_deg=rng.uniform(*cfg.rotation_deg),
                roundness=rng.uniform(*cfg.roundness),
                jitter=rng.uniform(*cfg.jitter),
            )
        )
    return styles


def style_stroke(
    polyline: np.ndarray,
    style: WriterStyle,
    rng: np.random.Generator,
    variation: float,
    points_per_unit: float,
) -> np.ndarray:
    """Apply a writer's style plus one sample's variation to a glyph polyline (y down).

    Parameters
    ----------
    polyline : ndarray, shape (m, 2)
        Joined glyph in font units (about 21 units from cap line to base line).
    style : WriterStyle
    rng : numpy Generator
        The sample's own random stream.
    variation : float
        Spread of the per-sample changes of slant, width and rotation.
    points_per_unit : float
        Sampling density of the returned stroke.

    Returns
    -------
    ndarray, shape (k, 2)
        The styled stroke, y down, in the writer's size (font units x size).
    """
    length = float(np.linalg.norm(np.diff(polyline, axis=0), axis=1).sum())
    if length <= 0:  # a single dot glyph: nothing to write
        raise UsageError("glyph has zero length")
    n = max(int(length * points_per_unit), 16)
    pts = resample_arclength(polyline, n)
    pts = gaussian_filter1d(pts, sigma=style.roundness * points_per_unit, axis=0, mode="nearest")

    # smooth jitter along the arc: a few random low-frequency sinusoids per axis
    arc = np.linspace(0.0, 1.0, n)[:, None]
    freqs = rng.uniform(0.5, 3.0, size=(1, 3))
    phases = rng.uniform(0, 2 * np.pi, size=(2, 3))
    amps = rng.normal(size=(2, 3)) * style.jitter * 21.0 / np.sqrt(3)
    for axis in range(2):
        pts[:, axis] += (amps[axis] * np.sin(2 * np.pi * freqs * arc + phases[axis])).sum(axis=1)

    slant = style.slant + rng.normal(0, variation)
    width = style.width * (1 + rng.normal(0, variation))
    angle = np.deg2rad(style.rotation_deg + rng.normal(0, 20 * variation))
    # y is down, so a rightward lean moves points with smaller y (higher up) to the right.
    # Shear, then rotate, written out rather than as matrix products: BLAS kernels differ by CPU
    # (with or without fused multiply-add) and would change the last bits of every stroke.
    x = width * pts[:, 0] - slant * pts[:, 1]
    y = pts[:, 1]
    cos, sin = np.cos(angle), np.sin(angle)
    return np.column_stack([cos * x - sin * y, sin * x + cos * y]) * style.size


def generate(cfg: SyntheticSettings) -> list[RawSample]:
    """All synthetic raw samples: writers x characters x sessions, deterministic for the seed.

    Returns
    -------
    list of RawSample
        ``n_writers * len(characters) * samples_per_char`` single-stroke samples, y down,
        ``source="synthetic"``; writer ids ``SYN_W01``..., session ids ``syn_W01-1``...
    """
    samples = []
    for w, style in enumerate(writer_styles(cfg)):
        glyphs = _font_glyphs(style.font)
        writer = f"SYN_W{w + 1:02d}"
        for session in range(cfg.samples_per_char):
            for c, ch in enumerate(cfg.characters):
                if ch not in glyphs:
                    raise UsageError(f"character {ch!r} is not in the synthetic alphabet")
                rng = np.random.default_rng(np.random.SeedSequence([cfg.seed, w, session, c]))
                stroke = style_stroke(
                    join_strokes(glyphs[ch]), style, rng, cfg.sample_variation, cfg.points_per_unit
                )
                samples.append(
                    RawSample(
                        char=ch,
                        writer=writer,
                        session=f"syn_W{w + 1:02d}-{session + 1}",
                        strokes=[stroke],
                        source="synthetic",
                    )
                )
    return samples
