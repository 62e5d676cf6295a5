"""Stimuli: robot and human handwriting samples, read from their files and drawn alike.

Every sample — the robot's ``prg-write`` word trajectory or a person's pen trajectory — becomes a
:class:`Sample` (strokes of points, y up, any unit) and is drawn by one renderer,
:func:`render_sample`, with one :class:`RenderStyle`: the same PNG size, margins and stroke width,
black ink on white, the word scaled to the same ink height (or width, when it is too wide) and
centred, so that nothing but the shape of the handwriting tells the samples apart (pressure,
timing and colour are dropped).

Human sample files (:func:`load_human_samples`, any mix, searched recursively):

* **capture JSON** written by the capture page (schema ``prg.handwriting_capture``, version 1): a
  writer's session, one entry per word; strokes of ``[x, y, t_ms, pressure]`` in CSS pixels,
  y down (see ``studies/web/capture.js``); ``delayed`` (optional: files from before it have
  none) lists the strokes the page kept as delayed strokes;
* **strokes JSON**: ``{"word": ..., "writer_id": ..., "strokes": [[[x, y], ...], ...],
  "y_down": true, "delayed": [1]}`` (``word``/``writer_id`` may come from the path, below;
  extra numbers per point are ignored; ``delayed`` is optional), or a ``prg.word_trajectory``
  file;
* **SVG**: the ``polyline``, ``line`` and ``path`` elements (``M L H V C S Q T Z``; arcs are
  drawn as straight lines), with their ``transform`` attributes.

A file without ``word``/``writer_id`` inside is named ``<writer_id>/<word>.json|svg``.

**Delayed strokes.** The word is one movement; the dots of the i's and j's and the bars of the
t's and f's may follow it as separate, small strokes (a :class:`Sample`'s ``delayed``). A sample
whose strokes after the first are all delayed strokes was not written with a pen lift; any
other extra stroke is a lift. The robot's marks (``"mark"`` segments of its word trajectory)
are its delayed strokes. A study's ``delayed_strokes`` setting decides for both: with False,
the delayed strokes of every sample are left undrawn (the paper's single stroke).

Robot samples: :func:`generate_robot_words` writes each word with ``prg-write``'s task function;
:func:`load_robot_words` reads ``<word>.json`` or ``<word>/word.json`` word trajectories.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
import xml.etree.ElementTree as ET
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from prg.errors import UsageError

ROBOT = "robot"  #: the writer id of robot samples (studies.design's trials use it too)
CAPTURE_SCHEMA = "prg.handwriting_capture"
CAPTURE_VERSION = 1
WORD_SCHEMA = "prg.word_trajectory"
HUMAN_SUFFIXES = (".json", ".svg")
#: The capture page's rule (``capture.delayed_max_size``): a stroke after the word is a delayed
#: stroke (a dot or a bar) when its bounding box is no taller than this fraction of the word
#: stroke's height and no wider than twice it; a larger one is a pen lift.
DELAYED_MAX_SIZE = 0.35


@dataclass(frozen=True)
class Sample:
    """One handwritten word.

    Attributes
    ----------
    word : str
    writer_id : str
        ``"robot"`` for the robot's sample.
    strokes : tuple of ndarray, each shape (n_i, 2)
        Pen-down strokes in writing order, y up, any unit.
    origin : str
        The file it came from.
    lifted : bool
        The writer lifted the pen (a capture flagged so, or strokes after the first that are
        not delayed strokes).
    delayed : tuple of int
        Indices into ``strokes`` of the delayed strokes: the dots and bars written after the
        word (the robot's marks; the strokes a capture kept as such). Never 0.
    """

    word: str
    writer_id: str
    strokes: tuple[np.ndarray, ...]
    origin: str = ""
    lifted: bool = False
    delayed: tuple[int, ...] = ()

    @property
    def source(self) -> str:
        """``"robot"`` or ``"human"``."""
        return ROBOT if self.writer_id == ROBOT else "human"

    def without_delayed(self) -> Sample:
        """The sample without its delayed strokes (the paper's single stroke)."""
        if not self.delayed:
            return self
        keep = tuple(s for i, s in enumerate(self.strokes) if i not in self.delayed)
        return replace(self, strokes=keep, delayed=())


MAX_RENDER_PX = 4000  #: a stimulus PNG's width or height
MAX_RENDER_PIXELS = 64_000_000  #: supersampled pixels drawn per stimulus (64 MB in grey)


@dataclass(frozen=True)
class RenderStyle:
    """How every stimulus is drawn.

    Attributes
    ----------
    width_px, height_px : int
        PNG size.
    margin_px : int
        Blank border on every side (ink never enters it).
    stroke_px : float
        Ink width.
    supersample : int
        Drawn this many times larger, then reduced (anti-aliasing).
    """

    width_px: int = 720
    height_px: int = 180
    margin_px: int = 14
    stroke_px: float = 4.0
    supersample: int = 4

    def __post_init__(self) -> None:
        for name, high in (
            ("width_px", MAX_RENDER_PX),
            ("height_px", MAX_RENDER_PX),
            ("supersample", 8),
        ):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= high:
                raise UsageError(
                    f"render.{name} must be an integer from 1 to {high}, got {value!r}"
                )
        if (
            isinstance(self.margin_px, bool)
            or not isinstance(self.margin_px, int)
            or self.margin_px < 0
        ):
            raise UsageError(f"render.margin_px must be an integer >= 0, got {self.margin_px!r}")
        if (
            isinstance(self.stroke_px, bool)
            or not isinstance(self.stroke_px, int | float)
            or not 0 < self.stroke_px < math.inf
        ):
            raise UsageError(
                f"render.stroke_px must be a positive finite number, got {self.stroke_px!r}"
            )
        drawn = self.width_px * self.height_px * self.supersample**2
        if drawn > MAX_RENDER_PIXELS:
            raise UsageError(
                f"render: width_px x height_px x supersample² is {drawn} pixels per stimulus; "
                f"at most {MAX_RENDER_PIXELS}"
            )
        inner = min(self.width_px, self.height_px) - 2 * self.margin_px - self.stroke_px
        if inner <= 0:
            raise UsageError("render: margins and stroke leave no room for the word")

    @classmethod
    def from_dict(cls, settings: dict) -> RenderStyle:
        """From the study's ``render`` section; names an unknown key."""
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(settings) - known)
        if unknown:
            raise UsageError(f"render: unknown key {unknown[0]!r}: accepted are {sorted(known)}")
        return cls(**settings)


# ---------------------------------------------------------------------------- rendering
def fit_transform(
    strokes: Sequence[np.ndarray], style: RenderStyle
) -> tuple[float, np.ndarray, np.ndarray]:
    """Scale and offsets that map y-up points to centred pixel coordinates (y down).

    The ink's bounding box is scaled to fill the room inside the margins (less half a stroke
    on each side) in height, or in width where the word is too wide, and centred.

    Returns
    -------
    scale : float
    center_in : ndarray, shape (2,)
        Centre of the ink's bounding box (input units).
    center_out : ndarray, shape (2,)
        Centre of the image (pixels).
    """
    pts = np.concatenate([np.asarray(s, dtype=np.float64).reshape(-1, 2) for s in strokes])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    size = hi - lo
    room = np.array(
        [
            style.width_px - 2 * style.margin_px - style.stroke_px,
            style.height_px - 2 * style.margin_px - style.stroke_px,
        ]
    )
    ratios = [room[d] / size[d] for d in range(2) if size[d] > 1e-12 * max(1.0, abs(hi[d]))]
    scale = min(ratios) if ratios else 1.0
    return scale, (lo + hi) / 2, np.array([style.width_px / 2, style.height_px / 2])


def to_pixels(strokes: Sequence[np.ndarray], style: RenderStyle) -> list[np.ndarray]:
    """Strokes (y up) in the PNG's pixel coordinates (y down), as :func:`fit_transform` maps."""
    scale, c_in, c_out = fit_transform(strokes, style)
    flip = np.array([1.0, -1.0])
    return [c_out + (np.asarray(s, float).reshape(-1, 2) - c_in) * scale * flip for s in strokes]


def render_strokes(strokes: Sequence[np.ndarray], style: RenderStyle) -> Image.Image:
    """Draw strokes (y up, any unit) as a grayscale image: black ink on white.

    Returns
    -------
    PIL.Image.Image
        Mode ``"L"``, size ``(style.width_px, style.height_px)``.
    """
    strokes = [np.asarray(s, dtype=np.float64).reshape(-1, 2) for s in strokes]
    strokes = [s for s in strokes if len(s)]
    if not strokes:
        raise UsageError("nothing to draw: the sample has no points")
    k = style.supersample
    image = Image.new("L", (style.width_px * k, style.height_px * k), 255)
    draw = ImageDraw.Draw(image)
    width = max(1, round(style.stroke_px * k))
    radius = width / 2
    for pts in to_pixels(strokes, style):
        big = [(float(x) * k, float(y) * k) for x, y in pts]
        if len(big) > 1:
            draw.line(big, fill=0, width=width, joint="curve")
        for x, y in (big[0], big[-1]):  # round caps
            draw.ellipse((x - radius, y - radius, x + radius, y + radius), fill=0)
    return image.reduce(k)  # box filter: anti-aliased, no ringing into the margins


def render_sample(sample: Sample, style: RenderStyle) -> Image.Image:
    """:func:`render_strokes` of a sample's strokes."""
    try:
        return render_strokes(sample.strokes, style)
    except UsageError as err:
        raise UsageError(f"{sample.origin or sample.word}: {err}") from None


def stimulus_name(sample: Sample, salt: str) -> str:
    """An opaque, stable file name for a sample's PNG (reveals neither word nor writer)."""
    digest = hashlib.sha256(f"{salt}|{sample.word}|{sample.writer_id}".encode()).hexdigest()
    return f"{digest[:16]}.png"


def save_png(image: Image.Image, path: Path) -> Path:
    """Write a PNG without metadata (no creation time, no software tag)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    image.save(path, format="PNG", optimize=True)
    return path


# ---------------------------------------------------------------------------- reading samples
def _points(raw, where: str) -> np.ndarray:
    try:
        rows = [list(p)[:2] for p in raw]
        pts = np.asarray(rows, dtype=np.float64).reshape(-1, 2)
    except (TypeError, ValueError):
        raise UsageError(f"{where}: a stroke must be a list of [x, y, ...] numbers") from None
    if not np.all(np.isfinite(pts)):
        raise UsageError(f"{where}: a stroke holds NaN or infinite numbers")
    return pts


def _strokes(
    raw, where: str, y_down: bool, delayed=None
) -> tuple[tuple[np.ndarray, ...], tuple[int, ...]]:
    """The non-empty strokes of ``raw`` (y up) and the indices among them of the delayed
    strokes that ``delayed`` lists (indices into ``raw``; None: none)."""
    if not isinstance(raw, list):
        raise UsageError(f"{where}: strokes must be a list of strokes, each a list of [x, y]")
    if delayed is None:
        delayed = []
    if (
        not isinstance(delayed, list)
        or not all(isinstance(k, int) and not isinstance(k, bool) for k in delayed)
        or not all(1 <= k < len(raw) for k in delayed)
        or len(set(delayed)) != len(delayed)
    ):
        accepted = f"1 to {len(raw) - 1}" if len(raw) > 1 else "none: there is one stroke"
        raise UsageError(
            f"{where}: delayed must list strokes after the first by index ({accepted}), "
            f"each once, got {delayed!r}"
        )
    out, kept = [], []
    for i, stroke in enumerate(raw):
        if not isinstance(stroke, list):
            raise UsageError(f"{where}: each stroke must be a list of [x, y] points")
        pts = _points(stroke, where)
        if len(pts):
            if i in delayed and out:  # a delayed stroke after an empty first one is the word
                kept.append(len(out))
            out.append(pts * [1.0, -1.0] if y_down else pts)
    return tuple(out), tuple(kept)


def is_lifted(n_strokes: int, delayed: Sequence[int], flagged: bool = False) -> bool:
    """Whether a sample was written with a pen lift: flagged so, or a stroke after the first
    that is not a delayed stroke."""
    return bool(flagged) or n_strokes - 1 > len(delayed)


def _identity_from_path(path: Path, root: Path) -> tuple[str | None, str | None]:
    """(word, writer_id) from ``<root>/.../<writer_id>/<word>.<ext>``."""
    rel = path.relative_to(root)
    writer = rel.parts[-2] if len(rel.parts) >= 2 else None
    return path.stem, writer


def read_capture(doc: dict, where: str) -> list[Sample]:
    """Samples of a capture-page document (schema ``prg.handwriting_capture``)."""
    if doc.get("version") != CAPTURE_VERSION:
        raise UsageError(
            f"{where}: capture version {doc.get('version')!r} is not supported "
            f"(accepted: {CAPTURE_VERSION})"
        )
    writer = doc.get("writer_id")
    if not isinstance(writer, str) or not writer.strip():
        raise UsageError(f"{where}: writer_id must be a non-empty string")
    y_down = bool(doc.get("canvas", {}).get("y_down", True))
    samples = doc.get("samples")
    if not isinstance(samples, list):
        raise UsageError(f"{where}: samples must be a list")
    out = []
    for i, entry in enumerate(samples):
        here = f"{where}: samples[{i}]"
        if not isinstance(entry, dict) or not isinstance(entry.get("word"), str):
            raise UsageError(f"{here} must be an object with word and strokes")
        strokes, delayed = _strokes(entry.get("strokes"), here, y_down, entry.get("delayed"))
        if not strokes:
            continue  # a skipped word
        lifted = is_lifted(len(strokes), delayed, entry.get("lifted", False))
        out.append(Sample(entry["word"], writer.strip(), strokes, where, lifted, delayed))
    return out


def read_json_sample(path: Path, root: Path) -> list[Sample]:
    """Samples in one JSON file: a capture, a strokes document or a word trajectory."""
    where = str(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as err:
        raise UsageError(f"{where}: cannot read ({err})") from None
    except json.JSONDecodeError as err:
        raise UsageError(f"{where}: not valid JSON ({err.msg} at line {err.lineno})") from None
    if isinstance(doc, dict) and doc.get("schema") == CAPTURE_SCHEMA:
        return read_capture(doc, where)
    word, writer = _identity_from_path(path, root)
    if isinstance(doc, dict) and doc.get("schema") == WORD_SCHEMA:
        from prg.pipeline.word import WordTrajectory

        traj = WordTrajectory.from_json(path)
        return [trajectory_sample(traj, _need(writer, where), where)]
    y_down, delayed = False, None
    if isinstance(doc, dict):
        word = doc.get("word", word)
        writer = doc.get("writer_id", writer)
        y_down = bool(doc.get("y_down", False))
        delayed = doc.get("delayed")
        doc = doc.get("strokes")
    strokes, delayed = _strokes(doc, where, y_down, delayed)
    if not strokes:
        raise UsageError(f"{where}: no strokes")
    lifted = is_lifted(len(strokes), delayed)
    return [Sample(str(word), _need(writer, where), strokes, where, lifted, delayed)]


def _need(writer: str | None, where: str) -> str:
    if not writer:
        raise UsageError(
            f"{where}: no writer_id: put it in the file or name the file <writer_id>/<word>.json"
        )
    return str(writer)


def _pen_down_runs(traj) -> list[tuple[int, int]]:
    """``(start, stop)`` point indices of each pen-down run of a word trajectory."""
    down = traj.pen_down()
    out, start = [], None
    for i, d in enumerate([*down.tolist(), False]):
        if d and start is None:
            start = i
        elif not d and start is not None:
            out.append((start, i))
            start = None
    return out


def word_strokes(traj) -> tuple[np.ndarray, ...]:
    """The ink of a :class:`prg.pipeline.word.WordTrajectory`: its pen-down runs (y up), the
    delayed strokes (its ``"mark"`` segments) included."""
    return tuple(traj.points[a:b].copy() for a, b in _pen_down_runs(traj))


def trajectory_sample(traj, writer_id: str, origin: str) -> Sample:
    """A word trajectory as a :class:`Sample`: its pen-down runs, the runs after the body
    (:attr:`~prg.pipeline.word.WordTrajectory.body_end`: the marks) as its delayed strokes."""
    runs = _pen_down_runs(traj)
    strokes = tuple(traj.points[a:b].copy() for a, b in runs)
    delayed = tuple(i for i, (a, _) in enumerate(runs) if i and a >= traj.body_end)
    return Sample(traj.text, writer_id, strokes, origin, False, delayed)


# -- SVG
_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_TOKEN = re.compile(rf"([MmLlHhVvCcSsQqTtAaZz])|({_NUM})")


def _matrix(transform: str | None, where: str) -> np.ndarray:
    m = np.eye(3)
    if not transform:
        return m
    for name, args in re.findall(r"(\w+)\s*\(([^)]*)\)", transform):
        v = [float(x) for x in re.findall(_NUM, args)]
        if name == "matrix" and len(v) == 6:
            t = np.array([[v[0], v[2], v[4]], [v[1], v[3], v[5]], [0, 0, 1]])
        elif name == "translate" and v:
            t = np.array([[1, 0, v[0]], [0, 1, v[1] if len(v) > 1 else 0], [0, 0, 1]])
        elif name == "scale" and v:
            sy = v[1] if len(v) > 1 else v[0]
            t = np.diag([v[0], sy, 1.0])
        elif name == "rotate" and v:
            a = math.radians(v[0])
            cx, cy = (v[1], v[2]) if len(v) == 3 else (0.0, 0.0)
            c, s = math.cos(a), math.sin(a)
            t = np.array([[c, -s, cx - c * cx + s * cy], [s, c, cy - s * cx - c * cy], [0, 0, 1]])
        else:
            raise UsageError(f"{where}: unsupported SVG transform {name}({args})")
        m = m @ t
    return m


def _bezier(points: Sequence[np.ndarray], n: int = 16) -> list[np.ndarray]:
    t = np.linspace(0, 1, n + 1)[1:, None]
    if len(points) == 3:
        p0, p1, p2 = points
        return list((1 - t) ** 2 * p0 + 2 * (1 - t) * t * p1 + t**2 * p2)
    p0, p1, p2, p3 = points
    return list((1 - t) ** 3 * p0 + 3 * (1 - t) ** 2 * t * p1 + 3 * (1 - t) * t**2 * p2 + t**3 * p3)


def path_strokes(d: str, where: str) -> list[np.ndarray]:
    """Polylines of an SVG path's ``d`` (curves sampled, arcs straight); each ``M`` starts one."""
    tokens = _TOKEN.findall(d)
    strokes: list[list[np.ndarray]] = []
    cur = np.zeros(2)
    start = np.zeros(2)
    last_ctrl: np.ndarray | None = None
    cmd = None
    i = 0

    def nums(k: int) -> list[float]:
        nonlocal i
        out = []
        for _ in range(k):
            if i >= len(tokens) or not tokens[i][1]:
                raise UsageError(f"{where}: malformed SVG path data near command {cmd!r}")
            out.append(float(tokens[i][1]))
            i += 1
        return out

    while i < len(tokens):
        if tokens[i][0]:
            cmd = tokens[i][0]
            i += 1
        elif cmd is None:
            raise UsageError(f"{where}: SVG path data must start with M")
        rel = cmd.islower()
        base = cur if rel else np.zeros(2)
        c = cmd.upper()
        if c == "Z":
            if strokes:
                strokes[-1].append(start.copy())
            cur = start.copy()
            last_ctrl = None
            continue
        if c == "M":
            cur = base + nums(2)
            start = cur.copy()
            strokes.append([cur.copy()])
            cmd = "l" if rel else "L"  # further pairs are line-tos
            last_ctrl = None
            continue
        if not strokes:
            strokes.append([cur.copy()])
        if c == "L":
            cur = base + nums(2)
            pts = [cur.copy()]
            last_ctrl = None
        elif c == "H":
            x = nums(1)[0]
            cur = np.array([cur[0] + x if rel else x, cur[1]])
            pts = [cur.copy()]
            last_ctrl = None
        elif c == "V":
            y = nums(1)[0]
            cur = np.array([cur[0], cur[1] + y if rel else y])
            pts = [cur.copy()]
            last_ctrl = None
        elif c in "CS":
            c1 = (2 * cur - last_ctrl if last_ctrl is not None else cur) if c == "S" else None
            if c == "C":
                c1 = base + nums(2)
            c2, end = base + nums(2), base + nums(2)
            pts = _bezier([cur, c1, c2, end])
            last_ctrl, cur = c2, end
        elif c in "QT":
            if c == "Q":
                q = base + nums(2)
            else:
                q = 2 * cur - last_ctrl if last_ctrl is not None else cur
            end = base + nums(2)
            pts = _bezier([cur, q, end])
            last_ctrl, cur = q, end
        else:  # A: rx ry rotation large-arc sweep x y, drawn straight
            end = base + nums(7)[5:]
            pts, cur, last_ctrl = [end.copy()], end, None
        strokes[-1].extend(pts)
    return [np.array(s) for s in strokes if len(s)]


def read_svg(path: Path, root: Path) -> list[Sample]:
    """One sample from an SVG file named ``<writer_id>/<word>.svg`` (y down in SVG)."""
    where = str(path)
    try:
        tree = ET.parse(path)
    except (OSError, ET.ParseError) as err:
        raise UsageError(f"{where}: not a readable SVG file ({err})") from None
    strokes: list[np.ndarray] = []

    def walk(node: ET.Element, m: np.ndarray) -> None:
        m = m @ _matrix(node.get("transform"), where)
        tag = node.tag.rsplit("}", 1)[-1]
        found: list[np.ndarray] = []
        if tag in ("polyline", "polygon"):
            v = [float(x) for x in re.findall(_NUM, node.get("points", ""))]
            pts = np.array(v[: len(v) // 2 * 2]).reshape(-1, 2)
            if tag == "polygon" and len(pts):
                pts = np.vstack([pts, pts[:1]])
            found = [pts]
        elif tag == "line":
            found = [
                np.array(
                    [
                        [float(node.get("x1", 0)), float(node.get("y1", 0))],
                        [float(node.get("x2", 0)), float(node.get("y2", 0))],
                    ]
                )
            ]
        elif tag == "path":
            found = path_strokes(node.get("d", ""), where)
        for pts in found:
            if len(pts):
                h = np.column_stack([pts, np.ones(len(pts))]) @ m.T
                strokes.append(h[:, :2] * [1.0, -1.0])
        for child in node:
            walk(child, m)

    walk(tree.getroot(), np.eye(3))
    if not strokes:
        raise UsageError(f"{where}: no polyline, line or path to read as pen strokes")
    word, writer = _identity_from_path(path, root)
    return [Sample(word, _need(writer, where), tuple(strokes), where, len(strokes) > 1)]


@dataclass
class HumanSamples:
    """Human samples found for a study.

    Attributes
    ----------
    by_word : dict of str to dict of str to Sample
        ``by_word[word][writer_id]``.
    notes : list of str
        Files and samples left out, and why.
    """

    by_word: dict[str, dict[str, Sample]] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    def writers(self) -> dict[str, list[str]]:
        """Writer ids per word, sorted."""
        return {w: sorted(s) for w, s in self.by_word.items()}


def load_human_samples(
    dirs: Iterable[str | Path],
    words: Sequence[str],
    accept_lifted: bool = False,
    delayed_strokes: bool = True,
) -> HumanSamples:
    """Read every human sample file under ``dirs`` (recursively) for the study's ``words``.

    Samples of other words, samples with a pen lift (unless ``accept_lifted``) and a second
    sample of the same word by the same writer are left out and listed in ``notes``. Delayed
    strokes (dots and bars written after the word) are no pen lift: the sample keeps them, or,
    with ``delayed_strokes`` False (the paper's single stroke), drops them with a note.

    Raises
    ------
    UsageError
        A folder that does not exist, or a file that cannot be read as a sample.
    """
    out = HumanSamples({w: {} for w in words})
    for root in dirs:
        root = Path(root)
        if not root.is_dir():
            raise UsageError(f"--human {root}: no such folder of human samples")
        for path in sorted(p for p in root.rglob("*") if p.suffix.lower() in HUMAN_SUFFIXES):
            if path.name.startswith(".") or not path.is_file():
                continue
            reader = read_svg if path.suffix.lower() == ".svg" else read_json_sample
            for sample in reader(path, root):
                if sample.word not in out.by_word:
                    out.notes.append(f"{path}: {sample.word!r} is not a study word; left out")
                elif sample.writer_id == ROBOT:
                    out.notes.append(f"{path}: writer id 'robot' is reserved; left out")
                elif sample.lifted and not accept_lifted:
                    out.notes.append(
                        f"{path}: {sample.writer_id}/{sample.word} was written with a pen lift; "
                        "left out (human.accept_lifted: true keeps it)"
                    )
                elif sample.writer_id in out.by_word[sample.word]:
                    out.notes.append(
                        f"{path}: a second {sample.word!r} by {sample.writer_id}; left out"
                    )
                else:
                    if sample.delayed and not delayed_strokes:
                        out.notes.append(
                            f"{path}: {sample.writer_id}/{sample.word}: its "
                            f"{len(sample.delayed)} delayed stroke(s) (dots, bars) are not drawn "
                            "(delayed_strokes: false)"
                        )
                        sample = sample.without_delayed()
                    out.by_word[sample.word][sample.writer_id] = sample
    return out


def held_out_words(
    words: Sequence[str],
    n: int,
    data_dir: str | Path,
    out_dir: str | Path,
    seed: int = 0,
    delayed_strokes: bool = True,
) -> dict[str, list[Sample]]:
    """Human words for a pilot: ``n`` writers of the dataset's test and validation splits
    (people no model was trained on) per word, each word made of that writer's own letters, laid out and joined the way the
    robot's are (:func:`prg.pipeline.compose.compose_word` with ``prg-write``'s settings), so
    that what tells them apart is the letters and the hand, not the joining. Writers who did
    not write every letter of a word are skipped for it. Each word is saved as
    ``<out_dir>/<writer>/<word>.json`` (its sample's origin).

    Raises
    ------
    UsageError
        If the splits cannot be read, or fewer than ``n`` writers wrote a word's letters.
    """
    from dataclasses import replace

    from prg.alphabet import char_to_label
    from prg.data.store import load_split
    from prg.pipeline.compose import GenerateSettings, compose_word

    splits = [load_split(Path(data_dir) / f"{name}.npz") for name in ("test", "val")]
    keep = [~split["augmented"] for split in splits]
    traj = np.concatenate([sp["traj"][k] for sp, k in zip(splits, keep, strict=True)])
    traj = traj.reshape(len(traj), -1, 2)
    labels = np.concatenate([sp["label"][k] for sp, k in zip(splits, keep, strict=True)])
    writers = np.concatenate(
        [sp["writer"][k].astype(str) for sp, k in zip(splits, keep, strict=True)]
    )
    names = sorted(set(writers))
    rng = np.random.default_rng([seed, 11])
    out: dict[str, list[Sample]] = {}
    for word in words:
        wanted = [char_to_label(c) for c in word if c != " "]
        able = [w for w in names if all(((writers == w) & (labels == y)).any() for y in wanted)]
        if len(able) < n:
            raise UsageError(
                f"pilot: only {len(able)} held-out writers wrote every letter of {word!r}; "
                f"{n} are needed"
            )
        out[word] = []
        for k, writer in enumerate(rng.choice(able, size=n, replace=False)):
            letters = np.stack(
                [traj[np.flatnonzero((writers == writer) & (labels == y))[0]] for y in wanted]
            )
            settings = replace(GenerateSettings(seed=k), delayed_strokes=delayed_strokes)
            traj_word, _ = compose_word(letters, word, settings)
            writer_id = f"pilot-{writer}"
            path = Path(out_dir) / writer_id / f"{word}.json"
            path.parent.mkdir(parents=True, exist_ok=True)
            traj_word.to_json(path)
            out[word].append(trajectory_sample(traj_word, writer_id, str(path)))
    return out


def stand_ins(
    robot: Sample, n: int, seed: int, amount: float = 0.08, delayed_strokes: bool = True
) -> list[Sample]:
    """``n`` placeholder "human" samples of the robot's word, for piloting a study before the
    human writers have written: the robot's strokes under a random shear/scale and a slow
    wobble, writers ``pilot01``, ``pilot02`` ... (``lifted`` False; never for real data).

    The robot's delayed strokes (its dots and bars, ``robot.delayed``) are kept as the stand-ins'
    delayed strokes, each moved with the part of the word nearest to it and keeping its own
    shape (a dot stays a dot); with ``delayed_strokes`` False they are left out.
    """
    if not delayed_strokes:
        robot = robot.without_delayed()
    pts = np.concatenate(robot.strokes)
    height = float(np.ptp(pts[:, 1])) or 1.0
    writing = [i for i in range(len(robot.strokes)) if i not in robot.delayed]
    anchors = np.concatenate([robot.strokes[i] for i in writing])
    out = []
    for k in range(n):
        rng = np.random.default_rng([seed, 5, k])
        a = np.eye(2) + rng.normal(0, amount, (2, 2))
        strokes: list[np.ndarray] = list(robot.strokes)
        shifts = []
        for i in writing:
            stroke = robot.strokes[i]
            u = np.linspace(0, 1, len(stroke))[:, None]
            wobble = np.sin(2 * np.pi * u * rng.uniform(1, 3, 2) + rng.uniform(0, 6, 2))
            strokes[i] = stroke @ a.T + wobble * amount * height * 0.5
            shifts.append(wobble * amount * height * 0.5)
        shift = np.concatenate(shifts)
        for i in robot.delayed:
            centre = robot.strokes[i].mean(axis=0)
            near = int(np.argmin(np.hypot(*(anchors - centre).T)))
            strokes[i] = robot.strokes[i] @ a.T + shift[near]
        out.append(
            Sample(
                robot.word,
                f"pilot{k + 1:02d}",
                tuple(strokes),
                "pilot stand-in",
                delayed=robot.delayed,
            )
        )
    return out


# ---------------------------------------------------------------------------- robot samples
def load_robot_words(
    folder: str | Path, words: Sequence[str], delayed_strokes: bool = True
) -> dict[str, Sample]:
    """Robot samples from ``<folder>/<word>.json`` or ``<folder>/<word>/word.json``.

    With ``delayed_strokes`` False a word's marks (its dots and bars) are left out: the body
    alone, the paper's single stroke, whatever the file holds.

    Raises
    ------
    UsageError
        The folder or a word's file is missing or is not a word trajectory of that word.
    """
    from prg.pipeline.word import WordTrajectory

    folder = Path(folder)
    if not folder.is_dir():
        raise UsageError(f"--robot {folder}: no such folder of word trajectories")
    out = {}
    for word in words:
        candidates = [folder / f"{word}.json", folder / word / "word.json"]
        path = next((p for p in candidates if p.is_file()), None)
        if path is None:
            raise UsageError(
                f"--robot {folder}: no word trajectory for {word!r} ({word}.json or "
                f"{word}/word.json, as prg-write writes)"
            )
        traj = WordTrajectory.from_json(path)
        if traj.text != word:
            raise UsageError(f"{path}: holds {traj.text!r}, expected {word!r}")
        sample = trajectory_sample(traj, ROBOT, str(path))
        out[word] = sample if delayed_strokes else sample.without_delayed()
    return out


def sets_delayed_strokes(override: str) -> bool:
    """Whether a ``prg-write`` override sets ``delayed_strokes`` (``delayed_strokes=...``,
    ``+``/``++``/``~`` forms too)."""
    key = override.partition("=")[0].strip().lstrip("+~").strip()
    return key == "delayed_strokes"


def unmarked_words(robot: dict[str, Sample]) -> list[str]:
    """Robot words with a letter that ``prg-write`` marks by default (dotted i/j, crossed t/f:
    :class:`prg.pipeline.marks.MarkSettings`) but no delayed stroke: words written with
    ``delayed_strokes=false`` (or by a version without marks)."""
    from prg.pipeline.marks import MarkSettings

    marks = MarkSettings()
    letters = set(marks.dotted + marks.crossed)
    return [w for w, s in robot.items() if not s.delayed and letters & set(w)]


def generate_robot_words(
    words: Sequence[str],
    out_dir: str | Path,
    family: str = "muse",
    ckpt: str | Path | None = None,
    overrides: Sequence[str] = (),
    progress: Callable[[str], None] | None = None,
    delayed_strokes: bool = True,
    hand_per_word: bool = True,
) -> dict[str, Path]:
    """Write each word with one :class:`prg.writer.Writer` (the model loaded once).

    Parameters
    ----------
    words : sequence of str
    out_dir : path
        Receives ``<word>.json`` (the word trajectories).
    family : str
        Model family; its checkpoint is ``models/<family>/model.ckpt`` unless ``ckpt`` is given.
    ckpt : path, optional
    overrides : sequence of str
        ``prg-write`` settings as its overrides (e.g. ``generate.temperature=0.3``); not
        ``delayed_strokes``, which is the argument below.
    progress : callable, optional
        Called with a line per word.
    delayed_strokes : bool
        Passed as ``prg-write``'s ``delayed_strokes``: True dots the i's and j's and crosses
        the t's and f's after the cursive word; False writes the paper's single stroke.
    hand_per_word : bool
        True (the study's ``robot.hands: per_word``): word ``i`` is written with
        ``generate.seed`` + ``i``, each in its own hand, as each trial's human words are by
        different people; False: every word with the one seed, in one hand.

    Returns
    -------
    dict of str to Path

    Raises
    ------
    UsageError
        A bad override (one that sets ``delayed_strokes`` too), a missing checkpoint.
    """
    from prg.checks import check_values
    from prg.commands.cli import compose_config
    from prg.commands.settings import writer_from_config

    if not isinstance(delayed_strokes, bool):
        raise UsageError(f"delayed_strokes must be true or false, got {delayed_strokes!r}")
    clash = next((o for o in overrides if sets_delayed_strokes(o)), None)
    if clash is not None:
        raise UsageError(
            f"robot.write_overrides: {clash!r}: delayed_strokes is set by the study's "
            "top-level delayed_strokes"
        )
    args = [f"family={family}", f"delayed_strokes={str(delayed_strokes).lower()}", *overrides]
    if ckpt is not None:
        args.append(f"ckpt={Path(ckpt).resolve()}")
    try:
        cfg = compose_config("write", args)
    except Exception as err:  # Hydra raises several types for a bad override
        message = " ".join(str(err).split())
        raise UsageError(f"robot.write_overrides: {message}") from None
    check_values(cfg)
    writer = writer_from_config(cfg)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = {}
    base = writer.settings
    for i, word in enumerate(words):
        if progress:
            progress(f"robot writes {word!r} ({i + 1}/{len(words)})")
        if hand_per_word:
            writer.settings = replace(base, seed=base.seed + i)
        paths[word] = writer.write(text=word).word.to_json(out_dir / f"{word}.json")
    return paths
