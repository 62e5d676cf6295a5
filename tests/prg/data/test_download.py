"""Tests of ``prg.data.download`` (moved from the suite on: tests of the atomic downloader and UJI
fetching against a real HTTP server on loopback)."""

from __future__ import annotations

import os
import signal
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest

from prg.data.download import (
    UJI_ARCHIVE,
    UJI_SHA256,
    UJI_URL,
    UjiSource,
    check_sha256,
    download,
    fetch_uji,
    resolve_uji_path,
)
from prg.data.uji import read_uji
from prg.errors import DownloadError, UsageError
from tests.helpers.download import FIXTURE, PAYLOAD, UJI_ZIP, Server, make_zip, server, sha  # noqa: F401 (fixtures)


def test_constants_point_at_uci_archive() -> None:
    assert UJI_URL.startswith("https://archive.ics.uci.edu/")
    assert UJI_URL.endswith(".zip")
    assert UJI_SHA256 is None or check_sha256(UJI_SHA256) == UJI_SHA256


def test_good_download(server: Server, tmp_path: Path) -> None:
    dest = tmp_path / "sub" / "file.bin"
    out = download(server.url("/file.bin"), dest, sha(PAYLOAD).upper(), progress=True)
    assert out == dest
    assert dest.read_bytes() == PAYLOAD
    assert os.listdir(dest.parent) == ["file.bin"]


def test_download_without_content_length(server: Server, tmp_path: Path) -> None:
    dest = tmp_path / "file.bin"
    download(server.url("/nolength"), dest, sha(PAYLOAD), progress=False)
    assert dest.read_bytes() == PAYLOAD


def test_checksum_mismatch_leaves_nothing(server: Server, tmp_path: Path) -> None:
    wrong = "0" * 64
    with pytest.raises(DownloadError, match="checksum mismatch") as info:
        download(server.url("/file.bin"), tmp_path / "file.bin", wrong, progress=False)
    message = str(info.value)
    assert server.url("/file.bin") in message
    assert wrong in message
    assert sha(PAYLOAD) in message
    assert "\n" not in message
    assert os.listdir(tmp_path) == []


def test_checksum_mismatch_keeps_previous_dest(server: Server, tmp_path: Path) -> None:
    dest = tmp_path / "file.bin"
    dest.write_bytes(b"old")
    with pytest.raises(DownloadError):
        download(server.url("/file.bin"), dest, "f" * 64, progress=False)
    assert dest.read_bytes() == b"old"
    assert os.listdir(tmp_path) == ["file.bin"]


def test_a_failed_move_into_place_names_the_destination(
    server: Server, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    dest = tmp_path / "file.bin"

    def refuse(src, dst):  # as a rename over a read-only destination fails
        raise PermissionError(13, "Permission denied", str(src), None, str(dst))

    monkeypatch.setattr(os, "replace", refuse)
    with pytest.raises(DownloadError) as info:
        download(server.url("/file.bin"), dest, sha(PAYLOAD), progress=False)
    assert str(info.value).endswith(f"Permission denied: '{dest}'")  # not the temporary name
    assert os.listdir(tmp_path) == []


def test_interrupted_transfer_leaves_nothing(server: Server, tmp_path: Path) -> None:
    with pytest.raises(DownloadError, match=r"cut short: received 1000 of 256000 bytes"):
        download(server.url("/short"), tmp_path / "file.bin", sha(PAYLOAD), progress=False)
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("route", ["/file.bin", "/nolength"], ids=["announced", "unannounced"])
def test_a_body_over_the_size_limit_is_refused_and_leaves_nothing(
    server: Server, tmp_path: Path, route: str
) -> None:
    """Announced (Content-Length) or not, a body over max_bytes is refused, naming the limit."""
    dest = tmp_path / "file.bin"
    dest.write_bytes(b"old")
    limit = len(PAYLOAD) - 1
    with pytest.raises(DownloadError, match=f"more than the limit of {limit} bytes"):
        download(server.url(route), dest, sha(PAYLOAD), progress=False, max_bytes=limit)
    assert dest.read_bytes() == b"old"
    assert os.listdir(tmp_path) == ["file.bin"]
    download(server.url(route), dest, sha(PAYLOAD), progress=False, max_bytes=len(PAYLOAD))
    assert dest.read_bytes() == PAYLOAD  # exactly at the limit is fine


def test_a_zip_member_larger_than_a_uji_file_is_refused(tmp_path: Path, monkeypatch) -> None:
    from prg.data import download as module

    archive = tmp_path / "uji.zip"
    archive.write_bytes(UJI_ZIP)
    dest = tmp_path / "ujipenchars2.txt"
    monkeypatch.setattr(module, "MAX_EXTRACT_BYTES", len(FIXTURE.read_bytes()) - 1)
    with pytest.raises(UsageError, match="more than the"):
        module.extract_uji(archive, dest)
    assert sorted(os.listdir(tmp_path)) == ["uji.zip"]


def test_http_404(server: Server, tmp_path: Path) -> None:
    with pytest.raises(DownloadError, match=r"/nothing-here failed: HTTP 404"):
        download(server.url("/nothing-here"), tmp_path / "x.bin", None, progress=False)
    assert os.listdir(tmp_path) == []


def test_unreachable_host(tmp_path: Path) -> None:
    srv = ThreadingHTTPServer(("127.0.0.1", 0), BaseHTTPRequestHandler)
    port = srv.server_address[1]
    srv.server_close()  # nothing listens there any more
    with pytest.raises(DownloadError, match=rf"cannot download http://127.0.0.1:{port}/"):
        download(f"http://127.0.0.1:{port}/x", tmp_path / "x.bin", None, progress=False)
    assert os.listdir(tmp_path) == []


@pytest.mark.skipif(not hasattr(signal, "setitimer"), reason="needs POSIX interval timers")
def test_keyboard_interrupt_leaves_nothing(server: Server, tmp_path: Path) -> None:
    def interrupt(signum: int, frame: object) -> None:
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGALRM, interrupt)
    signal.setitimer(signal.ITIMER_REAL, 0.3)
    try:
        with pytest.raises(DownloadError, match="interrupted; nothing was written"):
            download(server.url("/slow"), tmp_path / "file.bin", None, progress=False)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    assert os.listdir(tmp_path) == []


def test_unknown_checksum_warns_with_hash(
    server: Server, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    download(server.url("/file.bin"), tmp_path / "f.bin", None, progress=False, pin_hint="x.key")
    err = capsys.readouterr().err.strip()
    assert err == (
        f"warning: no SHA-256 to verify {server.url('/file.bin')} against; "
        f"the file has sha256 {sha(PAYLOAD)}; pin it with x.key={sha(PAYLOAD)}"
    )


def test_bad_checksum_value_is_usage_error(server: Server, tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="'abc' is not valid: expected 64 hexadecimal"):
        download(server.url("/file.bin"), tmp_path / "f.bin", "abc", progress=False)
    assert server.requests == []
    assert os.listdir(tmp_path) == []


def test_fetch_uji_extracts_and_reuses(server: Server, tmp_path: Path) -> None:
    url = server.url("/uji.zip")
    text = fetch_uji(tmp_path, url=url, sha256=sha(UJI_ZIP), progress=False)
    assert text == tmp_path / "raw" / "uji" / "ujipenchars2.txt"
    assert text.read_bytes() == FIXTURE.read_bytes()
    assert [s.char for s in read_uji(text)] == ["a", "A", "ñ", "ç", ";", "7"]
    assert sorted(os.listdir(text.parent)) == sorted(["ujipenchars2.txt", UJI_ARCHIVE])
    assert server.requests == ["/uji.zip"]

    fetch_uji(tmp_path, url=url, sha256=sha(UJI_ZIP), progress=False)
    assert server.requests == ["/uji.zip"]  # both files present and matching: nothing done

    text.write_bytes(b"damaged")
    fetch_uji(tmp_path, url=url, sha256=sha(UJI_ZIP), progress=False)
    assert text.read_bytes() == FIXTURE.read_bytes()  # re-extracted from the kept archive
    assert server.requests == ["/uji.zip"]

    (text.parent / UJI_ARCHIVE).unlink()
    fetch_uji(tmp_path, url=url, sha256=sha(UJI_ZIP), progress=False)
    assert server.requests == ["/uji.zip", "/uji.zip"]
    assert sorted(os.listdir(text.parent)) == sorted(["ujipenchars2.txt", UJI_ARCHIVE])


def test_fetch_uji_wrong_checksum_writes_nothing(server: Server, tmp_path: Path) -> None:
    with pytest.raises(DownloadError, match="checksum mismatch"):
        fetch_uji(tmp_path, url=server.url("/uji.zip"), sha256="1" * 64, progress=False)
    assert os.listdir(tmp_path / "raw" / "uji") == []


def test_fetch_uji_without_checksum_warns(
    server: Server, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = fetch_uji(tmp_path, url=server.url("/uji.zip"), sha256=None, progress=False)
    assert len(read_uji(text)) == 6
    assert f"pin it with data.uji_sha256={sha(UJI_ZIP)}" in capsys.readouterr().err


def test_fetch_uji_rejects_archive_without_data(server: Server, tmp_path: Path) -> None:
    server.routes["/other.zip"] = make_zip({"readme.md": b"x", "notes.md": b"y"})
    with pytest.raises(DownloadError, match=r"other\.zip is unusable: .*holds no ujipenchars2"):
        fetch_uji(tmp_path, url=server.url("/other.zip"), sha256=None, progress=False)
    assert os.listdir(tmp_path / "raw" / "uji") == []


def test_resolve_prefers_local_copy(server: Server, tmp_path: Path) -> None:
    assert (
        resolve_uji_path(UjiSource(str(FIXTURE), True, server.url("/uji.zip"), None), tmp_path)
        == FIXTURE
    )
    archive = tmp_path / "mine.zip"
    archive.write_bytes(UJI_ZIP)
    got = resolve_uji_path(UjiSource(str(archive), False, server.url("/uji.zip"), None), tmp_path)
    assert got == archive
    assert len(read_uji(got)) == 6
    assert server.requests == []


def test_resolve_local_path_errors(tmp_path: Path) -> None:
    missing = tmp_path / "nope.txt"
    with pytest.raises(UsageError, match=r"data\.uji_path=.*nope\.txt: no such file"):
        resolve_uji_path(UjiSource(str(missing), True, UJI_URL, UJI_SHA256), tmp_path)
    with pytest.raises(UsageError, match="no such file"):
        resolve_uji_path(UjiSource(str(tmp_path), True, UJI_URL, UJI_SHA256), tmp_path)
    bad_zip = tmp_path / "bad.zip"
    bad_zip.write_bytes(make_zip({"a.csv": b"1", "b.csv": b"2"}))
    with pytest.raises(UsageError, match=r"bad\.zip: the zip holds no ujipenchars2\.txt"):
        resolve_uji_path(UjiSource(str(bad_zip), True, UJI_URL, UJI_SHA256), tmp_path)


def test_resolve_without_path_or_download(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match=r"no UJI data: .*data\.uji_path=.*data\.download=true"):
        resolve_uji_path(UjiSource(None, False, UJI_URL, UJI_SHA256), tmp_path)
    with pytest.raises(UsageError, match="no UJI data"):
        resolve_uji_path(UjiSource("  ", False, UJI_URL, UJI_SHA256), tmp_path)


def test_resolve_downloads_then_reuses_fetched_copy(server: Server, tmp_path: Path) -> None:
    url, digest = server.url("/uji.zip"), sha(UJI_ZIP)
    fetched = resolve_uji_path(UjiSource(None, True, url, digest), tmp_path, progress=False)
    assert fetched == tmp_path / "raw" / "uji" / "ujipenchars2.txt"
    assert resolve_uji_path(UjiSource(None, False, url, digest), tmp_path) == fetched
    assert server.requests == ["/uji.zip"]
    with pytest.raises(UsageError, match="no UJI data"):  # a copy not matching the pin
        resolve_uji_path(UjiSource(None, False, url, "2" * 64), tmp_path)
