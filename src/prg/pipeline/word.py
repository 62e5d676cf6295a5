"""The word trajectory: one pen motion for a whole word (or line of words), in centimetres.

A :class:`WordTrajectory` is what the final processing map produces and what the DMP fitting, the
simulator and the studies consume. Its points are split into consecutive **segments**, each of
one kind:

* ``"letter"`` — a letter's own points (in the order of the non-space characters of ``text``);
* ``"connection"`` — the pen-down stroke joining two letters of one word
  (:mod:`prg.pipeline.connect`); a pair of letters already within ``delta`` has no connection
  segment, so two letter segments can be adjacent;
* ``"space"`` — a pen-up travel within the body: between the last letter of a word and the first
  of the next, when ``text`` holds several words on one line, or between two letters of a word
  where a writer lifts the pen (:func:`prg.pipeline.joins.lifts_pen`) (a straight path subdivided
  at ``delta``: the DMP stays one continuous motion; the simulator lifts the pen and renderings
  draw no ink there);
* ``"lift"`` — after the cursive **body** (the letters, connections and spaces, which one DMP
  writes), the pen-up travel to a delayed stroke (a straight path, points strictly between its
  ends);
* ``"mark"`` — a delayed stroke: the dot of an ``i``/``j`` or the bar of a ``t``/``f``
  (:mod:`prg.pipeline.marks`). Every mark follows a lift; marks are written after the body.

Files: :meth:`WordTrajectory.to_json` / :meth:`WordTrajectory.from_json` (schema
``prg.word_trajectory`` version 2, which added ``lift`` and ``mark``; version 1 files are read
too; floats round-trip exactly), :meth:`WordTrajectory.to_svg` and
:meth:`WordTrajectory.to_png`. Every file is written under a temporary name in the destination
folder and renamed into place, so a reader never sees half a file.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any
from xml.sax.saxutils import escape

import numpy as np

from prg.errors import UsageError
from prg.files import atomic_path
from prg.pipeline.connect import ConnectionResult
from prg.pipeline.layout import word_breaks
from prg.pipeline.settings import DEFAULT_SPEED_CM_S
from prg.plotting import CONNECTION, FIGURE_INK, MARK, PAPER, SPACE, hex_colour

if TYPE_CHECKING:  # the DMP module (scipy) is imported when a word has a DMP
    from prg.pipeline.dmp import DMP

SCHEMA = "prg.word_trajectory"
SCHEMA_VERSION = 2
READ_VERSIONS = (1, 2)
SEGMENT_KINDS = ("letter", "connection", "space", "lift", "mark")
PEN_UP_KINDS = ("space", "lift")
DELAYED_KINDS = ("lift", "mark")

# How each kind is drawn when highlighting: (colour, width as a fraction of the pen width, dashes)
_STYLES = {
    "letter": (hex_colour(FIGURE_INK), 1.0, None),
    "connection": (hex_colour(CONNECTION), 1.0, None),
    "space": (hex_colour(SPACE), 0.5, (3.0, 3.0)),
    "lift": (hex_colour(SPACE), 0.5, (1.0, 3.0)),
    "mark": (hex_colour(MARK), 1.0, None),
}
_INK = (hex_colour(FIGURE_INK), 1.0, None)


def _arc_length(points: np.ndarray) -> float:
    if points.shape[0] < 2:
        return 0.0
    d = np.diff(points, axis=0)
    return float(np.hypot(d[:, 0], d[:, 1]).sum())


@dataclass
class WordTrajectory:
    """A written word: points, their segments, the text, timing and (optionally) its DMP.

    Attributes
    ----------
    points : ndarray, shape (P, 2)
        The pen path in centimetres, baseline at ``y = 0``, y up.
    segment : ndarray of int, shape (P,)
        Segment id of each point: ``0, ..., S - 1``, non-decreasing, every segment non-empty.
    segment_kinds : list of str, length S
        ``"letter"``, ``"connection"``, ``"space"``, ``"lift"`` or ``"mark"`` per segment
        (module docstring).
    text : str
        The written text; its non-space characters are the letter segments, in order.
    dmp : DMP or None
        The DMP fitted to the body (the whole path but the delayed strokes, :attr:`body_end`) (:class:`prg.pipeline.dmp.DMP`); stored in the JSON
        document as :meth:`DMP.to_dict <prg.pipeline.dmp.DMP.to_dict>` (weights, start, goal,
        tau, basis ...).
    speed_cm_s : float
        Mean pen speed along the path (cm/s), from the writing config.
    duration_s : float, optional
        Time to write the whole path, delayed strokes included; computed as path length / speed
        when not given.
    """

    points: np.ndarray
    segment: np.ndarray
    segment_kinds: list[str]
    text: str
    dmp: DMP | None = None
    speed_cm_s: float = DEFAULT_SPEED_CM_S
    duration_s: float | None = field(default=None)

    def __post_init__(self) -> None:
        self.points = np.asarray(self.points, dtype=np.float64)
        self.segment = np.asarray(self.segment)
        self.segment_kinds = list(self.segment_kinds)
        if self.duration_s is None and self._speed_ok():
            self.duration_s = self.path_length / float(self.speed_cm_s)
        self.validate()

    def _speed_ok(self) -> bool:
        try:
            return math.isfinite(float(self.speed_cm_s)) and float(self.speed_cm_s) > 0
        except (TypeError, ValueError):
            return False

    # ------------------------------------------------------------------ checks and views
    def validate(self) -> None:
        """Check the invariants; raises :class:`UsageError` naming the first one broken."""
        pts, seg = self.points, self.segment
        if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] < 1:
            raise UsageError(f"points must have shape (P, 2) with P >= 1, got {pts.shape}")
        if not np.all(np.isfinite(pts)):
            raise UsageError("points contain NaN or infinite values")
        if seg.shape != (pts.shape[0],):
            raise UsageError(f"segment must have shape ({pts.shape[0]},), got {seg.shape}")
        if seg.dtype.kind not in "iu":
            if seg.dtype.kind != "f" or not np.all(seg == np.round(seg)):
                raise UsageError("segment ids must be integers")
            self.segment = seg = seg.astype(np.int64)
        else:
            self.segment = seg = seg.astype(np.int64)
        steps = np.diff(seg)
        if seg[0] != 0 or np.any((steps != 0) & (steps != 1)):
            raise UsageError("segment ids must run 0, 1, 2, ... in order, each segment non-empty")
        n_seg = int(seg[-1]) + 1
        if len(self.segment_kinds) != n_seg:
            raise UsageError(
                f"segment_kinds has {len(self.segment_kinds)} entries for {n_seg} segments"
            )
        bad = [k for k in self.segment_kinds if k not in SEGMENT_KINDS]
        if bad:
            raise UsageError(
                f"unknown segment kind {bad[0]!r}: accepted are {', '.join(SEGMENT_KINDS)}"
            )
        first_delayed = next(
            (k for k, kind in enumerate(self.segment_kinds) if kind in DELAYED_KINDS), n_seg
        )
        tail = self.segment_kinds[first_delayed:]
        if tail and (
            len(tail) % 2
            or tail[0::2] != ["lift"] * (len(tail) // 2)
            or tail[1::2] != ["mark"] * (len(tail) // 2)
        ):
            raise UsageError(
                "delayed strokes must come after the body as lift, mark, lift, mark, ... segments"
            )
        if first_delayed == 0:
            raise UsageError("the word has no body before its delayed strokes")
        if not isinstance(self.text, str):
            raise UsageError(f"text must be a string, got {type(self.text).__name__}")
        n_chars = sum(c != " " for c in self.text)
        n_letters = self.segment_kinds.count("letter")
        if n_chars != n_letters:
            raise UsageError(
                f"text {self.text!r} has {n_chars} characters but there are {n_letters} "
                "letter segments"
            )
        if self.dmp is not None:
            from prg.pipeline.dmp import DMP

            if not isinstance(self.dmp, DMP):
                raise UsageError(f"dmp must be a DMP or None, got {type(self.dmp).__name__}")
        if not self._speed_ok():
            raise UsageError(f"speed_cm_s must be a positive number, got {self.speed_cm_s!r}")
        self.speed_cm_s = float(self.speed_cm_s)
        try:
            duration = float(self.duration_s)
        except (TypeError, ValueError):
            raise UsageError(f"duration_s must be a number, got {self.duration_s!r}") from None
        if not (math.isfinite(duration) and duration >= 0):
            raise UsageError(f"duration_s must be a non-negative number, got {self.duration_s!r}")
        self.duration_s = duration

    @property
    def path_length(self) -> float:
        """Length of the whole path (cm), pen-up travel included."""
        return _arc_length(self.points)

    @property
    def n_segments(self) -> int:
        return len(self.segment_kinds)

    @property
    def body_end(self) -> int:
        """Number of points of the body (the cursive word the DMP writes): the points before the
        first delayed stroke's lift, or all of them."""
        kinds = np.array(self.segment_kinds, dtype=object)[self.segment]
        delayed = np.flatnonzero(np.isin(kinds, DELAYED_KINDS))
        return int(delayed[0]) if len(delayed) else len(self.points)

    @property
    def body(self) -> np.ndarray:
        """The body's points (what the DMP is fitted to), shape (:attr:`body_end`, 2)."""
        return self.points[: self.body_end]

    def delayed_strokes(self) -> list[tuple[str, np.ndarray]]:
        """``(kind, path)`` of each lift and mark after the body, in order; a lift's path runs
        from the previous segment's last point to the mark's first point."""
        out = []
        for k in range(self.n_segments):
            kind = self.segment_kinds[k]
            if kind == "lift":
                ends = [self.segment_points(k - 1)[-1:], self.segment_points(k)]
                out.append((kind, np.concatenate([*ends, self.segment_points(k + 1)[:1]])))
            elif kind == "mark":
                out.append((kind, self.segment_points(k)))
        return out

    def segment_points(self, k: int) -> np.ndarray:
        """Points of segment ``k``, shape (n_k, 2)."""
        return self.points[self.segment == k]

    @property
    def letters(self) -> list[tuple[str, np.ndarray]]:
        """``(character, points)`` of every letter segment, in writing order."""
        chars = [c for c in self.text if c != " "]
        ids = [k for k, kind in enumerate(self.segment_kinds) if kind == "letter"]
        return [(c, self.segment_points(k)) for c, k in zip(chars, ids)]

    def pen_down(self) -> np.ndarray:
        """Per point: False on pen-up (``"space"``, ``"lift"``) segments, shape (P,)."""
        kinds = np.array(self.segment_kinds, dtype=object)
        return ~np.isin(kinds[self.segment], PEN_UP_KINDS)

    # ------------------------------------------------------------------ JSON
    def to_dict(self) -> dict:
        """The JSON document (schema ``prg.word_trajectory``, version 2)."""
        return {
            "schema": SCHEMA,
            "version": SCHEMA_VERSION,
            "text": self.text,
            "units": "cm",
            "speed_cm_s": self.speed_cm_s,
            "duration_s": self.duration_s,
            "segment_kinds": list(self.segment_kinds),
            "segment": [int(s) for s in self.segment],
            "points": [[float(x), float(y)] for x, y in self.points],
            "dmp": None if self.dmp is None else self.dmp.to_dict(),
        }

    @classmethod
    def from_dict(cls, doc: dict) -> WordTrajectory:
        """Inverse of :meth:`to_dict`; raises :class:`UsageError` on a malformed document."""
        if not isinstance(doc, dict):
            raise UsageError("expected a JSON object")
        if doc.get("schema") != SCHEMA:
            raise UsageError(f"schema must be {SCHEMA!r}, got {doc.get('schema')!r}")
        if doc.get("version") not in READ_VERSIONS:
            raise UsageError(
                f"unsupported version {doc.get('version')!r}: accepted are "
                + ", ".join(map(str, READ_VERSIONS))
            )
        required = ("text", "speed_cm_s", "duration_s", "segment_kinds", "segment", "points")
        missing = [k for k in required if k not in doc]
        if missing:
            raise UsageError(f"missing field {missing[0]!r}")
        if doc.get("units", "cm") != "cm":
            raise UsageError(f"units must be 'cm', got {doc.get('units')!r}")
        if not isinstance(doc["segment_kinds"], list):
            raise UsageError("segment_kinds must be a list")
        try:
            points = np.array(doc["points"], dtype=np.float64)
            segment = np.array(doc["segment"])
        except (TypeError, ValueError):
            raise UsageError("points and segment must be numeric arrays") from None
        if points.size == 0:
            points = points.reshape(0, 2)
        return cls(
            points=points,
            segment=segment,
            segment_kinds=doc["segment_kinds"],
            text=doc["text"],
            dmp=_dmp_from_json(doc.get("dmp")),
            speed_cm_s=doc["speed_cm_s"],
            duration_s=doc["duration_s"],
        )

    def to_json(self, path: str | os.PathLike) -> Path:
        """Write the JSON document atomically; returns the path."""
        text = json.dumps(self.to_dict(), allow_nan=False, separators=(",", ":"))
        return _atomic_write(Path(path), lambda tmp: tmp.write_text(text + "\n", encoding="utf-8"))

    @classmethod
    def from_json(cls, path: str | os.PathLike) -> WordTrajectory:
        """Read a file written by :meth:`to_json`.

        Raises
        ------
        UsageError
            One line naming the file: missing, not JSON, or not a valid word trajectory.
        """
        path = Path(path)
        try:
            raw = path.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise UsageError(f"{path}: no such word trajectory file") from None
        except (OSError, UnicodeDecodeError) as err:
            raise UsageError(f"{path}: cannot read word trajectory ({err})") from None
        try:
            doc = json.loads(raw)
        except json.JSONDecodeError as err:
            raise UsageError(
                f"{path}: not valid JSON ({err.msg} at line {err.lineno}, column {err.colno})"
            ) from None
        try:
            return cls.from_dict(doc)
        except UsageError as err:
            raise UsageError(f"{path}: not a valid word trajectory: {err}") from None

    # ------------------------------------------------------------------ rendering
    def polylines(self, highlight: bool = True) -> list[tuple[str, np.ndarray]]:
        """``(kind, points)`` per drawn piece; each consecutive point pair is in one piece.

        A piece starts at the previous segment's last point (so the ink is continuous) unless
        that segment is pen-up or the piece is a mark (a stroke of its own); a pen-up piece ends
        at the next segment's first point. Without ``highlight``, pen-up pieces are dropped.
        """
        out = []
        kinds = self.segment_kinds
        for k, kind in enumerate(kinds):
            pts = self.segment_points(k)
            if k > 0 and kinds[k - 1] not in PEN_UP_KINDS and kind != "mark":
                pts = np.concatenate([self.segment_points(k - 1)[-1:], pts])
            if kind in PEN_UP_KINDS and k + 1 < len(kinds):
                pts = np.concatenate([pts, self.segment_points(k + 1)[:1]])
            if kind in PEN_UP_KINDS and not highlight:
                continue
            out.append((kind, pts))
        return out

    def _styled(self, highlight: bool) -> list[tuple[str, np.ndarray, tuple]]:
        """:meth:`polylines` with the style each is drawn in: (colour, width fraction, dashes)."""
        return [(k, pts, _STYLES[k] if highlight else _INK) for k, pts in self.polylines(highlight)]

    def _corners(self, margin_cm: float) -> tuple[np.ndarray, np.ndarray]:
        """Lower-left and upper-right corners of a drawing of the points with a margin (cm)."""
        return self.points.min(axis=0) - margin_cm, self.points.max(axis=0) + margin_cm

    def to_svg(
        self,
        path: str | os.PathLike,
        highlight: bool = True,
        pen_width_cm: float = 0.04,
        margin_cm: float = 0.3,
    ) -> Path:
        """Draw the word as SVG, 1 user unit = 1 cm, written atomically; returns the path.

        Parameters
        ----------
        highlight : bool
            True: letters black, connections red, delayed strokes (marks) purple, pen-up travel grey
            dashed (each polyline has ``class`` = its kind). False: all pen-down ink black, pen-up travel not drawn (what
            a reader of the handwriting sees).
        pen_width_cm, margin_cm : float
        """
        lo, hi = self._corners(margin_cm)
        w, h = hi - lo
        lines = [
            '<?xml version="1.0" encoding="UTF-8"?>',
            f'<svg xmlns="http://www.w3.org/2000/svg" width="{w:.4f}cm" height="{h:.4f}cm" '
            f'viewBox="0 0 {w:.6f} {h:.6f}">',
            f"<title>{escape(self.text)}</title>",
            f'<rect width="100%" height="100%" fill="{hex_colour(PAPER)}"/>',
        ]
        for kind, pts, (colour, rel_width, dashes) in self._styled(highlight):
            coords = " ".join(f"{x - lo[0]:.5f},{hi[1] - y:.5f}" for x, y in pts)
            dash = ""
            if dashes:
                dash = ' stroke-dasharray="{}"'.format(
                    ",".join(f"{d * pen_width_cm * rel_width:.4f}" for d in dashes)
                )
            lines.append(
                f'<polyline class="{kind}" points="{coords}" fill="none" stroke="{colour}" '
                f'stroke-width="{pen_width_cm * rel_width:.4f}" stroke-linecap="round" '
                f'stroke-linejoin="round"{dash}/>'
            )
        lines.append("</svg>")
        svg = "\n".join(lines) + "\n"
        return _atomic_write(Path(path), lambda tmp: tmp.write_text(svg, encoding="utf-8"))

    def to_png(
        self,
        path: str | os.PathLike,
        highlight: bool = True,
        dpi: int = 150,
        pen_width_cm: float = 0.04,
    ) -> Path:
        """Draw the word as PNG, true to scale (``dpi``), in the styles of :meth:`to_svg` (round
        caps and joins, dashed pen-up travel), written atomically; returns the path.

        Drawn with Pillow at :data:`PNG_SUPERSAMPLE` times the resolution and reduced, for smooth
        edges: matplotlib draws the same but costs a command most of a second to import.
        """
        from PIL import Image, ImageDraw

        lo, hi = self._corners(0.3)
        size = np.maximum(np.ceil((hi - lo) / 2.54 * dpi), dpi // 2).astype(int)  # >= 0.5 in
        scale = dpi / 2.54 * PNG_SUPERSAMPLE  # pixels of the drawing per cm
        image = Image.new("RGB", tuple(int(n) * PNG_SUPERSAMPLE for n in size), PAPER)
        draw = ImageDraw.Draw(image)
        for _, pts, (colour, rel_width, dashes) in self._styled(highlight):
            width = pen_width_cm * rel_width * scale
            pixels = np.column_stack([pts[:, 0] - lo[0], hi[1] - pts[:, 1]]) * scale
            pieces = dash_pieces(pixels, [d * width for d in dashes]) if dashes else [pixels]
            for piece in pieces:
                draw.line([tuple(p) for p in piece], fill=colour, width=round(width), joint="curve")
                for x, y in (piece[0], piece[-1]):  # round caps
                    r = width / 2
                    draw.ellipse((x - r, y - r, x + r, y + r), fill=colour)
        image = image.reduce(PNG_SUPERSAMPLE)
        return _atomic_write(Path(path), lambda tmp: image.save(tmp, format="PNG", dpi=(dpi, dpi)))


PNG_SUPERSAMPLE = 4  # WordTrajectory.to_png draws at this multiple of its resolution


def dash_pieces(points: np.ndarray, pattern: Sequence[float]) -> list[np.ndarray]:
    """The dashes of the polyline ``points`` under ``pattern`` (on, off, on, off, ... lengths
    in the points' units, repeated from the start): one polyline per dash, its ends
    interpolated on the segments where a dash starts or stops."""
    steps = np.hypot(*np.diff(points, axis=0).T)
    along = np.concatenate([[0.0], np.cumsum(steps)])
    period = float(sum(pattern))
    if period <= 0 or along[-1] == 0:
        return [points]
    bounds = np.cumsum([0.0, *pattern])
    pieces = []
    for start in np.arange(0.0, along[-1], period):
        for on, off in zip(bounds[0::2], bounds[1::2]):
            a, b = start + on, min(start + off, along[-1])
            if a >= b:
                continue
            inside = (along > a) & (along < b)
            ends = [np.interp(t, along, points[:, d]) for t in (a, b) for d in (0, 1)]
            pieces.append(np.vstack([ends[:2], points[inside], ends[2:]]))
    return pieces


def _dmp_from_json(value: Any) -> DMP | None:
    """The ``dmp`` of a JSON document: None, or a DMP's ``to_dict()`` (validated)."""
    if value is None:
        return None
    if not isinstance(value, dict):
        raise UsageError(f"dmp must be a dict or None, got {type(value).__name__}")
    from prg.pipeline.dmp import DMP

    try:
        return DMP.from_dict(value)
    except UsageError as err:
        raise UsageError(f"invalid DMP ({err})") from None


def _atomic_write(path: Path, write: Callable[[Path], object]) -> Path:
    """Call ``write(tmp)`` on a temporary file next to ``path``, then rename it to ``path``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        write(tmp)
    return path


def assemble_word(
    letter_trajs_cm: Sequence[np.ndarray],
    connections: Sequence[ConnectionResult | np.ndarray],
    text: str,
    speed_cm_s: float = DEFAULT_SPEED_CM_S,
    dmp: DMP | None = None,
    marks: Sequence[np.ndarray] = (),
) -> WordTrajectory:
    """Concatenate laid-out letters, their connections and the delayed strokes into a
    :class:`WordTrajectory`.

    Parameters
    ----------
    letter_trajs_cm : sequence of ndarray, each shape (n_i, 2)
        The letters in centimetres (:func:`prg.pipeline.layout.layout_letters`), one per
        non-space character of ``text``.
    connections : sequence of ConnectionResult or ndarray of shape (k, 2)
        One per consecutive letter pair: the points strictly between the two letters
        (:func:`prg.pipeline.connect.connect_sequence`). Where ``text`` has a space between the
        two letters, or the entry is a pen-up travel (``ConnectionResult.pen_up``), it becomes a
        ``"space"`` segment; otherwise a ``"connection"`` segment. Empty entries add no segment.
    text : str
    speed_cm_s : float
        Writing speed; ``duration_s`` = path length / speed.
    dmp : DMP, optional
    marks : sequence of ndarray, each shape (m, 2)
        Delayed strokes written after the body, in order (:func:`prg.pipeline.marks.
        letter_marks`); each becomes a ``"lift"`` segment (pen-up travel from where the pen is)
        and a ``"mark"`` segment.

    Returns
    -------
    WordTrajectory
    """
    letters = [np.asarray(p, dtype=np.float64) for p in letter_trajs_cm]
    n_chars = sum(c != " " for c in text)
    if len(letters) != n_chars or not letters:
        raise UsageError(
            f"text {text!r} has {n_chars} characters but {len(letters)} letter trajectories "
            "were given (at least one is needed)"
        )
    if len(connections) != len(letters) - 1:
        raise UsageError(
            f"{len(letters)} letters need {len(letters) - 1} connections, got {len(connections)}"
        )
    breaks = word_breaks(text)
    pieces: list[np.ndarray] = []
    kinds: list[str] = []
    for i, letter in enumerate(letters):
        if letter.ndim != 2 or letter.shape[1] != 2 or letter.shape[0] < 1:
            raise UsageError(f"letter {i} must have shape (n, 2), got {letter.shape}")
        pieces.append(letter)
        kinds.append("letter")
        if i < len(connections):
            conn = connections[i]
            pts = conn.points if isinstance(conn, ConnectionResult) else conn
            pts = np.asarray(pts, dtype=np.float64).reshape(-1, 2)
            if pts.shape[0]:
                pieces.append(pts)
                pen_up = breaks[i] or (isinstance(conn, ConnectionResult) and conn.pen_up)
                kinds.append("space" if pen_up else "connection")
    for mark in marks:
        mark = np.asarray(mark, dtype=np.float64)
        if mark.ndim != 2 or mark.shape[1] != 2 or mark.shape[0] < 2:
            raise UsageError(f"a delayed stroke must have shape (m >= 2, 2), got {mark.shape}")
        pieces.append(travel_points(pieces[-1][-1], mark[0]))
        kinds.append("lift")
        pieces.append(mark)
        kinds.append("mark")
    segment = np.concatenate([np.full(p.shape[0], k, dtype=np.int64) for k, p in enumerate(pieces)])
    return WordTrajectory(
        points=np.concatenate(pieces, axis=0),
        segment=segment,
        segment_kinds=kinds,
        text=text,
        dmp=dmp,
        speed_cm_s=speed_cm_s,
    )


TRAVEL_STEP_CM = 0.1


def travel_points(
    start: np.ndarray, end: np.ndarray, step_cm: float = TRAVEL_STEP_CM
) -> np.ndarray:
    """The straight pen-up path from ``start`` to ``end``: points ``step_cm`` apart or closer,
    strictly between the two (at least the midpoint), shape (k >= 1, 2)."""
    start, end = np.asarray(start, dtype=np.float64), np.asarray(end, dtype=np.float64)
    n = max(2, int(np.ceil(np.hypot(*(end - start)) / step_cm)))
    u = np.linspace(0.0, 1.0, n + 1)[1:-1, None]
    return start + u * (end - start)
