"""Reading SVG sample files as pen strokes, with vpype (:func:`vpype.read_svg`).

The ``polyline``, ``polygon``, ``line`` and ``path`` elements are the pen strokes, each ``M``
of a path starting one; their ``transform`` attributes (and their groups') apply. The file is
read in its own user units: its ``viewBox``, ``width`` and ``height`` are not applied (the
renderer scales every sample to the same size anyway). Curves (``C S Q T A``) are sampled in
segments no longer than :data:`QUANTIZATION` of the drawing's size. Rectangles, circles,
ellipses, text and images are not pen strokes and are left out.
"""

from __future__ import annotations

import io
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from prg.errors import UsageError
from studies.stimuli.sample import Sample, _identity_from_path, _need

SVG_NS = "http://www.w3.org/2000/svg"
#: Elements vpype reads that are no pen strokes (a background, a frame, a label).
NOT_STROKES = frozenset({"rect", "circle", "ellipse", "text", "image"})
#: Curves are sampled in segments no longer than this fraction of the larger side of the
#: drawing's bounding box (vpype's ``quantization``): on a 720-pixel stimulus, under a pixel.
QUANTIZATION = 1e-3
_COMMAND = re.compile(r"\s*([A-Za-z])")


def _tag(node: ET.Element) -> str:
    return node.tag.rsplit("}", 1)[-1] if isinstance(node.tag, str) else ""


def _check_path(node: ET.Element, where: str) -> None:
    """Refuse malformed path data (vpype would drop the path silently); a path that starts
    with a command other than ``M`` starts at the origin."""
    from svgelements import Path as SvgPath

    d = node.get("d", "").strip()
    if not d:
        return
    first = _COMMAND.match(d)
    if first is None:
        raise UsageError(f"{where}: SVG path data must start with M")
    if first.group(1) not in "Mm":
        d = f"M 0 0 {d}"
        node.set("d", d)
    try:
        SvgPath(d)
    except (ValueError, IndexError):
        raise UsageError(f"{where}: malformed SVG path data {d[:40]!r}") from None


def _pen_strokes_only(root: ET.Element, where: str) -> str:
    """The document as vpype is to read it: strokes alone, in user units, tags in the SVG
    namespace (a file may omit it); its text."""
    for parent in list(root.iter()):
        for child in list(parent):
            tag = _tag(child)
            points = re.findall(
                r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?", child.get("points", "")
            )
            if tag in NOT_STROKES or (tag in ("polyline", "polygon") and len(points) < 2):
                parent.remove(child)
            elif tag == "path":
                _check_path(child, where)
    for node in root.iter():
        if isinstance(node.tag, str):
            node.tag = _tag(node)
    for key in ("viewBox", "width", "height"):
        root.attrib.pop(key, None)
    if root.get("transform"):  # not every reader applies the root's own transform: a group's
        group = ET.Element("g", {"transform": root.attrib.pop("transform")})
        group.extend(list(root))
        root[:] = [group]
    root.set("xmlns", SVG_NS)
    return ET.tostring(root, encoding="unicode")


def _polylines(text: str) -> list[np.ndarray]:
    """The polylines (y down, user units) of an SVG document's text, curves sampled at
    :data:`QUANTIZATION` of the drawing's size."""
    import svgelements
    import vpype

    box = svgelements.SVG.parse(io.StringIO(text)).bbox()
    size = max(box[2] - box[0], box[3] - box[1]) if box is not None else 0.0
    quantization = QUANTIZATION * size if size > 0 else QUANTIZATION
    lines, _, _ = vpype.read_svg(io.StringIO(text), quantization=quantization, crop=False)
    return [np.column_stack([line.real, line.imag]) for line in lines if len(line)]


def path_strokes(d: str, where: str) -> list[np.ndarray]:
    """Polylines of an SVG path's ``d`` (y down, curves sampled); each ``M`` starts one."""
    path = ET.Element("path", {"d": d})
    root = ET.Element("svg")
    root.append(path)
    return _polylines(_pen_strokes_only(root, where))


def read_svg(path: Path, root: Path) -> list[Sample]:
    """One sample from an SVG file named ``<writer_id>/<word>.svg`` (y down in SVG)."""
    where = str(path)
    try:
        tree = ET.parse(path)
    except (OSError, ET.ParseError) as err:
        raise UsageError(f"{where}: not a readable SVG file ({err})") from None
    try:
        lines = _polylines(_pen_strokes_only(tree.getroot(), where))
    except (ValueError, TypeError, IndexError) as err:  # svgelements: a value it cannot read
        raise UsageError(f"{where}: not a readable SVG file ({err})") from None
    strokes = tuple(line * [1.0, -1.0] for line in lines)
    if not strokes:
        raise UsageError(f"{where}: no polyline, line or path to read as pen strokes")
    word, writer = _identity_from_path(path, root)
    return [Sample(word, _need(writer, where), strokes, where, len(strokes) > 1)]
