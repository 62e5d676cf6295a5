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
  y down (see ``studies/web/capture.js``);
* **strokes JSON**: ``{"word": ..., "writer_id": ..., "strokes": [[[x, y], ...], ...],
  "y_down": true}`` (``word``/``writer_id`` may come from the path, below; extra numbers per
  point are ignored), or a ``prg.word_trajectory`` file;
* **SVG**: the ``polyline``, ``line`` and ``path`` elements (``M L H V C S Q T Z``; arcs are
  drawn as straight lines), with their ``transform`` attributes.

A file without ``word``/``writer_id`` inside is named ``<writer_id>/<word>.json|svg``.

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
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from prg.errors import UsageError

ROBOT = "robot"  #: the writer id of robot samples (studies.design's trials use it too)
CAPTURE_SCHEMA = "prg.handwriting_capture"
CAPTURE_VERSION = 1
WORD_SCHEMA = "prg.word_trajectory"
HUMAN_SUFFIXES = (".json", ".svg")


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
        The writer lifted the pen (a capture flagged so, or several strokes).
    """

    word: str
    writer_id: str
    strokes: tuple[np.ndarray, ...]
    origin: str = ""
    lifted: bool = False

    @property
    def source(self) -> str:
        """``"robot"`` or ``"human"``."""
        return ROBOT if self.writer_id == ROBOT else "human"


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


def _strokes(raw, where: str, y_down: bool) -> tuple[np.ndarray, ...]:
    if not isinstance(raw, list):
        raise UsageError(f"{where}: strokes must be a list of strokes, each a list of [x, y]")
    out = []
    for stroke in raw:
        if not isinstance(stroke, list):
            raise UsageError(f"{where}: each stroke must be a list of [x, y] points")
        pts = _points(stroke, where)
        if len(pts):
            out.append(pts * [1.0, -1.0] if y_down else pts)
    return tuple(out)


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
        strokes = _strokes(entry.get("strokes"), here, y_down)
        if not strokes:
            continue  # a skipped word
        lifted = bool(entry.get("lifted", False)) or len(strokes) > 1
        out.append(Sample(entry["word"], writer.strip(), strokes, where, lifted))
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
        return [Sample(traj.text, _need(writer, where), word_strokes(traj), where)]
    y_down = False
    if isinstance(doc, dict):
        word = doc.get("word", word)
        writer = doc.get("writer_id", writer)
        y_down = bool(doc.get("y_down", False))
        doc = doc.get("strokes")
    strokes = _strokes(doc, where, y_down)
    if not strokes:
        raise UsageError(f"{where}: no strokes")
    return [Sample(str(word), _need(writer, where), strokes, where, len(strokes) > 1)]


def _need(writer: str | None, where: str) -> str:
    if not writer:
        raise UsageError(
            f"{where}: no writer_id: put it in the file or name the file <writer_id>/<word>.json"
        )
    return str(writer)


def word_strokes(traj) -> tuple[np.ndarray, ...]:
    """The ink of a :class:`prg.pipeline.word.WordTrajectory`: its pen-down runs (y up)."""
    down = traj.pen_down()
    out, start = [], None
    for i, d in enumerate([*down.tolist(), False]):
        if d and start is None:
            start = i
        elif not d and start is not None:
            out.append(traj.points[start:i].copy())
            start = None
    return tuple(out)


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
    dirs: Iterable[str | Path], words: Sequence[str], accept_lifted: bool = False
) -> HumanSamples:
    """Read every human sample file under ``dirs`` (recursively) for the study's ``words``.

    Samples of other words, samples with a pen lift (unless ``accept_lifted``) and a second
    sample of the same word by the same writer are left out and listed in ``notes``.

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
                    out.by_word[sample.word][sample.writer_id] = sample
    return out


def stand_ins(robot: Sample, n: int, seed: int, amount: float = 0.08) -> list[Sample]:
    """``n`` placeholder "human" samples of the robot's word, for piloting a study before the
    human writers have written: the robot's strokes under a random shear/scale and a slow
    wobble, writers ``pilot01``, ``pilot02`` ... (``lifted`` False; never for real data).
    """
    pts = np.concatenate(robot.strokes)
    height = float(np.ptp(pts[:, 1])) or 1.0
    out = []
    for k in range(n):
        rng = np.random.default_rng([seed, 5, k])
        a = np.eye(2) + rng.normal(0, amount, (2, 2))
        strokes = []
        for stroke in robot.strokes:
            u = np.linspace(0, 1, len(stroke))[:, None]
            wobble = np.sin(2 * np.pi * u * rng.uniform(1, 3, 2) + rng.uniform(0, 6, 2))
            strokes.append(stroke @ a.T + wobble * amount * height * 0.5)
        out.append(Sample(robot.word, f"pilot{k + 1:02d}", tuple(strokes), "pilot stand-in"))
    return out


# ---------------------------------------------------------------------------- robot samples
def load_robot_words(folder: str | Path, words: Sequence[str]) -> dict[str, Sample]:
    """Robot samples from ``<folder>/<word>.json`` or ``<folder>/<word>/word.json``.

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
        out[word] = Sample(word, ROBOT, word_strokes(traj), str(path))
    return out


def generate_robot_words(
    words: Sequence[str],
    out_dir: str | Path,
    family: str = "muse",
    ckpt: str | Path | None = None,
    overrides: Sequence[str] = (),
    progress: Callable[[str], None] | None = None,
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
        ``prg-write`` settings as its overrides (e.g. ``generate.temperature=0.3``).
    progress : callable, optional
        Called with a line per word.

    Returns
    -------
    dict of str to Path
    """
    from prg.checks import check_values
    from prg.commands.cli import compose_config
    from prg.commands.settings import writer_from_config

    args = [f"family={family}", *overrides]
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
    for i, word in enumerate(words):
        if progress:
            progress(f"robot writes {word!r} ({i + 1}/{len(words)})")
        paths[word] = writer.write(text=word).word.to_json(out_dir / f"{word}.json")
    return paths
