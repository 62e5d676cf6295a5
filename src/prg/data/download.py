"""Atomic, checksum-verified downloads, and fetching the UJI Pen Characters v2 data.

A download streams into a hidden ``.<name>.tmp-<pid>`` file next to its destination,
hashing as it goes, and only a complete, verified file is moved into place
(:func:`prg.files.move_into_place`, an atomic rename) as the destination. Any failure removes the
partial file and raises :class:`~prg.errors.DownloadError`.
"""

from __future__ import annotations

import hashlib
import http.client
import os
import re
import shutil
import sys
import urllib.error
import urllib.request
import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

from tqdm import tqdm

from prg.data.uji import UJI_MEMBER, find_member
from prg.errors import DownloadError, UsageError
from prg.files import move_into_place, remove_stale, sha256_file

UJI_URL = "https://archive.ics.uci.edu/static/public/177/uji+pen+characters+version+2.zip"
"""The UCI ML repository archive of UJI Pen Characters (Version 2), dataset 177 (CC BY 4.0)."""

UJI_SHA256: str | None = "0881b522911b99d9922820289441b50fd3d307f71cd7f9cc70e86872424a5f90"
"""SHA-256 of the archive at :data:`UJI_URL`, as pinned by two independent public projects
(not verified here against a fresh download; override with ``data.uji_sha256=<hash>``)."""

UJI_ARCHIVE = "uji-pen-characters-v2.zip"
"""File name the archive is kept under, in ``<data_dir>/raw/uji/``."""

_CHUNK = 1 << 16

MAX_DOWNLOAD_BYTES = 256 * 2**20
"""Largest body :func:`download` accepts by default (the UJI archive is about 4 MB)."""

MAX_EXTRACT_BYTES = 512 * 2**20
"""Largest data file :func:`extract_uji` writes (the UJI text is about 30 MB); a larger one is a
corrupt or hostile archive (a zip bomb)."""
_HEX64 = re.compile(r"[0-9a-f]{64}")


def check_sha256(value: str | None) -> str | None:
    """Normalise a SHA-256 given by the user (lower case, 64 hex digits) or ``None``.

    Raises
    ------
    UsageError
        If ``value`` is not 64 hexadecimal digits.
    """
    if value is None or not str(value).strip():
        return None
    digest = str(value).strip().lower()
    if not _HEX64.fullmatch(digest):
        raise UsageError(f"SHA-256 {value!r} is not valid: expected 64 hexadecimal digits")
    return digest


def _temp_beside(dest: Path) -> tuple[BinaryIO, Path]:
    """An open, hidden temporary file in ``dest``'s folder, named the way :mod:`prg.files` names
    them (a killed download's file is removed by the next write there)."""
    dest.parent.mkdir(parents=True, exist_ok=True)
    remove_stale(dest.parent)
    part = dest.with_name(f".{dest.name}.tmp-{os.getpid()}")
    return part.open("wb"), part


def _too_large(url: str, size: int, limit: int) -> DownloadError:
    return DownloadError(
        f"download of {url} refused: {size} bytes is more than the limit of {limit} bytes"
    )


def _stream(
    url: str, out: BinaryIO, *, timeout: float, progress: bool, label: str, max_bytes: int
) -> str:
    """Copy the body at ``url`` into ``out``, at most ``max_bytes``; return its hex SHA-256."""
    request = urllib.request.Request(url, headers={"User-Agent": "prg-downloader/0.1"})
    try:
        response = urllib.request.urlopen(request, timeout=timeout)
    except urllib.error.HTTPError as exc:
        exc.close()
        raise DownloadError(f"download of {url} failed: HTTP {exc.code} {exc.reason}") from None
    except urllib.error.URLError as exc:
        raise DownloadError(f"cannot download {url}: {exc.reason}") from None
    with response:
        header = response.headers.get("Content-Length", "").strip()
        total = int(header) if header.isdigit() else None
        if total is not None and total > max_bytes:
            raise _too_large(url, total, max_bytes)
        digest = hashlib.sha256()
        received = 0
        with tqdm(
            total=total,
            unit="B",
            unit_scale=True,
            unit_divisor=1024,
            desc=label,
            disable=not progress,
            leave=False,
        ) as bar:
            while chunk := response.read(_CHUNK):
                digest.update(chunk)
                out.write(chunk)
                received += len(chunk)
                if received > max_bytes:  # no (or a false) Content-Length
                    raise _too_large(url, received, max_bytes)
                bar.update(len(chunk))
    if total is not None and received != total:
        raise DownloadError(
            f"download of {url} was cut short: received {received} of {total} bytes"
        )
    return digest.hexdigest()


def download(
    url: str,
    dest: Path,
    sha256: str | None,
    *,
    timeout: float = 60,
    progress: bool = True,
    pin_hint: str | None = None,
    max_bytes: int = MAX_DOWNLOAD_BYTES,
) -> Path:
    """Download ``url`` to ``dest`` atomically, verifying its SHA-256.

    Parameters
    ----------
    url : str
        Source URL (any scheme urllib supports).
    dest : Path
        Destination file; its folder is created. It is only written (replaced) once the whole
        body has arrived and matched ``sha256``.
    sha256 : str or None
        Expected hex SHA-256. ``None`` skips the check and prints a one-line warning with the
        computed hash to stderr.
    timeout : float
        Socket timeout in seconds, for connecting and for each read.
    progress : bool
        Show a tqdm progress bar on stderr.
    pin_hint : str, optional
        Config key named in the warning when ``sha256`` is ``None`` (e.g. ``data.uji_sha256``).
    max_bytes : int
        Largest body accepted: a larger Content-Length is refused before the body is read, a
        body without one is cut off there.

    Returns
    -------
    Path
        ``dest``.

    Raises
    ------
    DownloadError
        On an HTTP error, an unreachable host, a dropped connection, a body shorter than its
        Content-Length, a body over ``max_bytes``, a checksum mismatch or a KeyboardInterrupt.
        No partial file remains and
        ``dest`` is left as it was.
    UsageError
        If ``sha256`` is not 64 hex digits.
    """
    expected = check_sha256(sha256)
    dest = Path(dest)
    out, part = _temp_beside(dest)
    try:
        with out:
            actual = _stream(
                url, out, timeout=timeout, progress=progress, label=dest.name, max_bytes=max_bytes
            )
        if expected is not None and actual != expected:
            raise DownloadError(
                f"checksum mismatch for {url}: expected sha256 {expected}, got {actual}"
            )
        move_into_place(part, dest)
    except BaseException as exc:
        part.unlink(missing_ok=True)
        if isinstance(exc, DownloadError):
            raise
        if isinstance(exc, KeyboardInterrupt):
            raise DownloadError(f"download of {url} interrupted; nothing was written") from None
        if isinstance(exc, OSError | http.client.HTTPException | ValueError):
            raise DownloadError(f"download of {url} failed: {exc}") from None
        raise
    if expected is None:
        pin = f"; pin it with {pin_hint}={actual}" if pin_hint else ""
        print(
            f"warning: no SHA-256 to verify {url} against; the file has sha256 {actual}{pin}",
            file=sys.stderr,
        )
    return dest


def extract_uji(archive: Path, dest: Path) -> Path:
    """Extract ``ujipenchars2.txt`` from a zip archive to ``dest`` atomically.

    Raises
    ------
    UsageError
        If ``archive`` is not a readable zip holding the data file (CRC errors included).
    """
    out, part = _temp_beside(dest)
    try:
        with out, zipfile.ZipFile(archive) as zipped:
            member = find_member(zipped)
            if member is None:
                raise UsageError(f"zip archive {archive} holds no {UJI_MEMBER}")
            size = member.file_size
            if size > MAX_EXTRACT_BYTES:
                raise UsageError(
                    f"zip archive {archive}: {member} would be {size} bytes, more than the "
                    f"{MAX_EXTRACT_BYTES} bytes a UJI data file can be"
                )
            with zipped.open(member) as source:  # reads no more than the declared size
                shutil.copyfileobj(source, out, _CHUNK)
        move_into_place(part, dest)
    except BaseException as exc:
        part.unlink(missing_ok=True)
        if isinstance(exc, zipfile.BadZipFile | OSError):
            raise UsageError(f"cannot extract {UJI_MEMBER} from {archive}: {exc}") from None
        raise
    return dest


def _matches_member(archive: Path, text: Path) -> bool:
    """True if ``text`` has the size and CRC-32 of the archive's data member."""
    try:
        with zipfile.ZipFile(archive) as zipped:
            member = find_member(zipped)
        if member is None or text.stat().st_size != member.file_size:
            return False
        crc = 0
        with text.open("rb") as handle:
            while chunk := handle.read(_CHUNK):
                crc = zlib.crc32(chunk, crc)
    except (zipfile.BadZipFile, OSError):
        return False
    return crc == member.CRC


def _archive_ok(archive: Path, expected: str | None) -> bool:
    return archive.is_file() and (expected is None or sha256_file(archive) == expected)


def _cached(folder: Path, expected: str | None) -> Path | None:
    """The extracted file if it can be reused as is, else ``None``.

    With a known checksum, the kept archive must match it and the text must match the archive's
    member; without one, an existing text file is reused.
    """
    text, archive = folder / UJI_MEMBER, folder / UJI_ARCHIVE
    if not text.is_file():
        return None
    if expected is None:
        return text
    if _archive_ok(archive, expected) and _matches_member(archive, text):
        return text
    return None


def fetch_uji(
    data_dir: Path,
    url: str = UJI_URL,
    sha256: str | None = UJI_SHA256,
    progress: bool = True,
) -> Path:
    """Download the UJI archive (verified) and extract ``ujipenchars2.txt`` from it.

    Files live in ``<data_dir>/raw/uji/``: the archive as ``uji-pen-characters-v2.zip`` and the
    data as ``ujipenchars2.txt``. Nothing is fetched when both are already there and match
    (see :func:`_cached`); a kept archive that matches ``sha256`` is re-extracted, not
    re-downloaded.

    Returns
    -------
    Path
        ``<data_dir>/raw/uji/ujipenchars2.txt``.

    Raises
    ------
    DownloadError
        If the download fails or the archive does not hold the data file.
    """
    expected = check_sha256(sha256)
    folder = Path(data_dir) / "raw" / "uji"
    cached = _cached(folder, expected)
    if cached is not None:
        return cached
    text, archive = folder / UJI_MEMBER, folder / UJI_ARCHIVE
    if expected is None or not _archive_ok(archive, expected):
        download(url, archive, expected, progress=progress, pin_hint="data.uji_sha256")
    try:
        return extract_uji(archive, text)
    except UsageError as exc:
        archive.unlink(missing_ok=True)
        raise DownloadError(f"the archive downloaded from {url} is unusable: {exc}") from None


@dataclass(frozen=True)
class UjiSource:
    """Where the UJI data comes from (``data.uji_path``, ``data.download``, ``data.uji_url`` and
    ``data.uji_sha256`` in the Hydra config).

    Attributes
    ----------
    path : str or None
        A local ``ujipenchars2.txt`` or the UCI ``.zip`` (both are read by
        :func:`prg.data.uji.read_uji`); used as is, without a checksum check.
    download : bool
        Whether fetching from ``url`` is allowed when no usable copy is present.
    url, sha256 : str, str or None
        The archive and its expected SHA-256 (:func:`fetch_uji`).
    """

    path: str | None = None
    download: bool = False
    url: str = UJI_URL
    sha256: str | None = UJI_SHA256


def resolve_uji_path(source: UjiSource, data_dir: Path, *, progress: bool = True) -> Path:
    """Where to read the UJI data from: the user's copy, a fetched copy, or a new download.

    Parameters
    ----------
    source : UjiSource
        The user's copy, if any, and whether and from where to download one.
    data_dir : Path
        Data root; fetched files go to ``<data_dir>/raw/uji/``.
    progress : bool
        Show a progress bar while downloading.

    Raises
    ------
    UsageError
        If ``source.path`` is missing, unreadable or a zip without the data file, or if there is
        no path, no usable fetched copy and ``source.download`` is false.
    DownloadError
        If the download fails.
    """
    uji_path, url, sha256 = source.path, source.url, source.sha256
    if uji_path is not None and str(uji_path).strip():
        path = Path(str(uji_path).strip()).expanduser()
        if not path.is_file():
            raise UsageError(
                f"data.uji_path={uji_path}: no such file; give the path of {UJI_MEMBER} "
                "or of the UCI zip archive"
            )
        try:
            with path.open("rb") as handle:
                handle.read(1)
            if zipfile.is_zipfile(path):
                with zipfile.ZipFile(path) as zipped:
                    if find_member(zipped) is None:
                        raise UsageError(f"data.uji_path={uji_path}: the zip holds no {UJI_MEMBER}")
        except (OSError, zipfile.BadZipFile) as exc:
            raise UsageError(f"data.uji_path={uji_path}: cannot read it ({exc})") from None
        return path
    if source.download:
        return fetch_uji(data_dir, url=url, sha256=sha256, progress=progress)
    cached = _cached(Path(data_dir) / "raw" / "uji", check_sha256(sha256))
    if cached is not None:
        return cached
    raise UsageError(
        f"no UJI data: give a local copy with data.uji_path=/path/to/{UJI_MEMBER} (or the UCI "
        "zip), or allow downloading it with data.download=true"
    )
