"""Reader for the UJI Pen Characters v2 file ``ujipenchars2.txt`` (UCI ML repository, id 177).

The file (UTF-8, CRLF line ends) holds 11,640 samples: 60 writers x 97 characters x 2 sessions.
Lines starting with ``//`` are comments. Each sample is::

    WORD <char> <session-id>
      NUMSTROKES <n>
      POINTS <k> # x1 y1 x2 y2 ... xk yk      (n such lines)

Coordinates are integer ink units, origin at the top left of the acquisition box, **y down**
(negative values occur). A session id such as ``trn_UJI_W03-01`` is the *long writer id*
``trn_UJI_W03`` (writer set ``trn``/``tst``, site ``UJI``/``UPV``, writer number ``W01..W60``)
followed by ``-`` and the repetition ``01`` or ``02``.

Writer-id rule: the writer is the session id with a trailing ``-<digits>`` repetition suffix
removed (``trn_UJI_W03-01`` -> ``trn_UJI_W03``), so both sessions of a person share it. An id
without such a suffix is used whole as the writer id.
"""

from __future__ import annotations

import re
import zipfile
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

from prg.alphabet import is_supported
from prg.data.samples import RawSample
from prg.errors import DataFormatError, UsageError

UJI_MEMBER = "ujipenchars2.txt"
"""Name of the data file, alone or inside the UCI zip archive."""

_SESSION_SUFFIX = re.compile(r"-\d+$")
_FORMAT_HINT = "expected UJI Pen Characters v2 format: WORD/NUMSTROKES/POINTS"


def writer_from_session(session: str) -> str:
    """Writer id of a session id: the id without its trailing ``-<digits>`` repetition suffix.

    Examples
    --------
    >>> writer_from_session("tst_UPV_W45-02")
    'tst_UPV_W45'
    >>> writer_from_session("someone")
    'someone'
    """
    return _SESSION_SUFFIX.sub("", session) or session


MAX_COORDINATE = 2**31 - 1  # UJI's tablet coordinates are a few thousand units


def split_lines(text: str) -> list[str]:
    """Split ``text`` on LF, CRLF or lone CR only (no other Unicode line breaks)."""
    return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")


class _Entry:
    """A sample being parsed: its WORD line and the strokes read so far."""

    __slots__ = ("char", "line", "num_line", "num_strokes", "session", "strokes")

    def __init__(self, char: str, session: str, line: int):
        self.char = char
        self.session = session
        self.line = line
        self.num_strokes: int | None = None
        self.num_line = 0
        self.strokes: list[np.ndarray] = []


def _positive_int(token: str, what: str, path: str, line: int) -> int:
    try:
        value = int(token)
    except ValueError:
        raise DataFormatError(
            f"{what} must be a positive integer, got {token!r}", path=path, line=line
        ) from None
    if value <= 0:
        raise DataFormatError(
            f"{what} must be a positive integer, got {value}", path=path, line=line
        )
    return value


def _parse_points(rest: str, path: str, line: int) -> np.ndarray:
    """Parse ``<k> # x1 y1 ...`` (the text after ``POINTS``) into a (k, 2) float array."""
    head, sep, tail = rest.partition("#")
    if not sep:
        raise DataFormatError("POINTS line has no '#' before its coordinates", path=path, line=line)
    count_tokens = head.split()
    if len(count_tokens) != 1:
        raise DataFormatError(
            f"POINTS line needs one point count before '#', got {head.strip()!r}",
            path=path,
            line=line,
        )
    k = _positive_int(count_tokens[0], "POINTS count", path, line)
    try:  # fast path: C parser; anything it rejects is diagnosed below
        values = np.fromstring(tail, dtype=np.int64, sep=" ")
    except ValueError:
        values = None
    # numpy's parser clamps out-of-range integers to the int64 limits instead of failing
    if values is None or values.size != 2 * k or np.abs(values).max() > MAX_COORDINATE:
        values = _diagnose_coordinates(tail, k, path, line)
    return values.astype(np.float64).reshape(k, 2)


def _diagnose_coordinates(tail: str, k: int, path: str, line: int) -> np.ndarray:
    """Slow, exact check of a POINTS line's coordinates; raises on the first problem."""
    tokens = tail.split()
    if len(tokens) % 2:
        raise DataFormatError(
            f"POINTS line has an odd number of coordinates ({len(tokens)}); expected x y pairs",
            path=path,
            line=line,
        )
    if len(tokens) != 2 * k:
        raise DataFormatError(
            f"POINTS count is {k} but the line has {len(tokens) // 2} coordinate pairs",
            path=path,
            line=line,
        )
    for token in tokens:
        if not _is_int(token):
            raise DataFormatError(f"coordinate {token!r} is not an integer", path=path, line=line)
        if abs(int(token)) > MAX_COORDINATE:
            raise DataFormatError(
                f"coordinate {token} is out of range: accepted are integers within "
                f"+-{MAX_COORDINATE:,} (tablet units)",
                path=path,
                line=line,
            )
    return np.array([int(t) for t in tokens], dtype=np.int64)


def _is_int(token: str) -> bool:
    try:
        int(token)
    except ValueError:
        return False
    return True


def _finish(entry: _Entry, path: str, next_line: int | None) -> RawSample:
    """Check that ``entry`` is complete and turn it into a sample."""
    where = f"line {next_line}" if next_line is not None else "the end of the file"
    if entry.num_strokes is None:
        raise DataFormatError(
            f"entry 'WORD {entry.char} {entry.session}' has no NUMSTROKES line before {where}",
            path=path,
            line=entry.line,
        )
    if len(entry.strokes) != entry.num_strokes:
        raise DataFormatError(
            f"NUMSTROKES {entry.num_strokes} but only {len(entry.strokes)} POINTS lines "
            f"follow before {where}",
            path=path,
            line=entry.num_line,
        )
    return RawSample(
        char=entry.char,
        writer=writer_from_session(entry.session),
        session=entry.session,
        strokes=entry.strokes,
        source="uji",
        line=entry.line,
    )


def parse_uji(lines: Iterable[str], path: str = "<string>") -> list[RawSample]:
    """Parse UJI Pen Characters v2 text into samples, in file order.

    Parameters
    ----------
    lines : iterable of str
        The file's lines (line ends are stripped; a single ``str`` is split on LF/CRLF/CR).
    path : str
        Name used in error messages.

    Returns
    -------
    list of RawSample
        Every entry, whatever its character or number of strokes. Coordinates are float64
        copies of the integer ink units, y down.

    Raises
    ------
    DataFormatError
        On a malformed line, naming ``path`` and the 1-based line number.
    UsageError
        If the text holds no entry at all.
    """
    if isinstance(lines, str):
        lines = split_lines(lines)
    samples: list[RawSample] = []
    entry: _Entry | None = None

    def malformed(message: str) -> DataFormatError:  # about the line being read
        return DataFormatError(message, path=path, line=number)

    for number, raw in enumerate(lines, start=1):
        parts = (raw.lstrip("\ufeff") if number == 1 else raw).split(None, 1)
        if not parts or parts[0].startswith("//"):
            continue
        keyword = parts[0]
        rest = parts[1] if len(parts) == 2 else ""
        if keyword == "WORD":
            fields = rest.split()
            if len(fields) != 2:
                raise malformed(
                    f"WORD line needs a character and a session id, got {rest.strip()!r}"
                )
            if entry is not None:
                samples.append(_finish(entry, path, number))
            entry = _Entry(fields[0], fields[1], number)
        elif keyword == "NUMSTROKES":
            if entry is None:
                raise malformed("NUMSTROKES outside an entry (no WORD line before it)")
            if entry.num_strokes is not None:
                raise malformed(f"second NUMSTROKES line in the entry started at line {entry.line}")
            fields = rest.split()
            if len(fields) != 1:
                raise malformed(f"NUMSTROKES line needs one count, got {rest.strip()!r}")
            entry.num_strokes = _positive_int(fields[0], "NUMSTROKES", path, number)
            entry.num_line = number
        elif keyword == "POINTS":
            if entry is None:
                raise malformed("POINTS outside an entry (no WORD line before it)")
            if entry.num_strokes is None:
                raise malformed(
                    f"POINTS line before NUMSTROKES in the entry started at line {entry.line}"
                )
            if len(entry.strokes) == entry.num_strokes:
                raise malformed(
                    f"more POINTS lines than NUMSTROKES {entry.num_strokes} (line {entry.num_line})"
                )
            entry.strokes.append(_parse_points(rest, path, number))
        else:
            shown = keyword if len(keyword) <= 40 else keyword[:40] + "..."
            raise malformed(
                f"unknown line starting with {shown!r}; {_FORMAT_HINT} or '//' comments"
            )
    if entry is not None:
        samples.append(_finish(entry, path, None))
    if not samples:
        raise UsageError(f"no samples found in {path}: {_FORMAT_HINT}")
    return samples


def _decode(data: bytes) -> str:
    """UTF-8 (BOM allowed), falling back to latin-1 for files re-saved by old editors."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def find_member(archive: zipfile.ZipFile) -> zipfile.ZipInfo | None:
    """The ``ujipenchars2.txt`` entry of a zip archive (at any depth), else its only ``.txt``."""
    infos = [i for i in archive.infolist() if not i.is_dir()]
    named = [i for i in infos if i.filename.rsplit("/", 1)[-1] == UJI_MEMBER]
    if named:
        return named[0]
    texts = [i for i in infos if i.filename.lower().endswith(".txt")]
    return texts[0] if len(texts) == 1 else None


def read_uji(path: str | Path) -> list[RawSample]:
    """Read ``ujipenchars2.txt``, or the UCI zip archive that contains it.

    Parameters
    ----------
    path : str or Path
        The text file, or a ``.zip`` holding it (recognised by its content).

    Returns
    -------
    list of RawSample
        See :func:`parse_uji`.

    Raises
    ------
    UsageError
        If the file cannot be read, is a zip without the data file, or holds no entry.
    DataFormatError
        On a malformed line.
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise UsageError(f"cannot read UJI file {path}: {exc.strerror or exc}") from None
    name = str(path)
    if data.startswith(b"PK\x03\x04"):
        try:
            with zipfile.ZipFile(path) as archive:
                member = find_member(archive)
                if member is None:
                    raise UsageError(f"zip archive {path} holds no {UJI_MEMBER}")
                data = archive.read(member)
                name = f"{path}:{member.filename}"
        except (zipfile.BadZipFile, OSError) as exc:
            raise UsageError(f"cannot read zip archive {path}: {exc}") from None
    return parse_uji(split_lines(_decode(data)), path=name)


def select_single_stroke_alphabet(
    samples: Sequence[RawSample],
) -> tuple[list[RawSample], dict[str, int]]:
    """Keep samples of the 62-class alphabet written with exactly one stroke.

    Returns
    -------
    kept : list of RawSample
        The kept samples, in input order.
    counts : dict
        ``total``, ``kept``, ``dropped_not_in_alphabet`` (character outside 0-9, A-Z, a-z) and
        ``dropped_multi_stroke`` (in the alphabet but more than one stroke).
    """
    kept: list[RawSample] = []
    not_in_alphabet = multi_stroke = 0
    for sample in samples:
        if not is_supported(sample.char):
            not_in_alphabet += 1
        elif sample.num_strokes != 1:
            multi_stroke += 1
        else:
            kept.append(sample)
    counts = {
        "total": len(samples),
        "kept": len(kept),
        "dropped_not_in_alphabet": not_in_alphabet,
        "dropped_multi_stroke": multi_stroke,
    }
    return kept, counts


def format_uji(samples: Sequence[RawSample]) -> str:
    """Write samples in the UJI Pen Characters v2 text format (integer coordinates, LF ends).

    The inverse of :func:`parse_uji` up to rounding of coordinates: useful to export a dataset
    (e.g. the synthetic one) for tools that read UJI files.
    """
    lines = ["// UJI Pen Characters v2 format, written by prg"]
    for sample in samples:
        lines.append(f"WORD {sample.char} {sample.session}")
        lines.append(f"  NUMSTROKES {sample.num_strokes}")
        for stroke in sample.strokes:
            coords = " ".join(f"{round(float(x))} {round(float(y))}" for x, y in stroke)
            lines.append(f"    POINTS {len(stroke)} # {coords}")
    return "\n".join(lines) + "\n"
