"""Tests of the UJI Pen Characters v2 reader on real files in the official format."""

from __future__ import annotations

import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

from prg.data.samples import RawSample
from prg.data.uji import (
    parse_uji,
    read_uji,
    select_single_stroke_alphabet,
    writer_from_session,
)
from prg.errors import DataFormatError, UsageError

FIXTURE = Path(__file__).parents[2] / "fixtures" / "uji_small.txt"


# the second stroke of the semicolon in the format description of the UCI page
SEMICOLON_STROKE_2 = [[518, 1227], [500, 1257], [480, 1291], [470, 1309]]


SEMICOLON_STROKE_2 += [[465, 1318], [458, 1330], [458, 1330], [471, 1312]]


EXPECTED = [
    # char, writer, session, WORD line, strokes
    ("a", "trn_UJI_W01", "trn_UJI_W01-01", 5, [[[10, 20], [11, 22], [13, 25], [-2, 30]]]),
    ("A", "trn_UJI_W01", "trn_UJI_W01-02", 10, [[[100, 200], [110, 210], [120, 220]]]),
    ("ñ", "trn_UJI_W01", "trn_UJI_W01-01", 14, [[[1, 2], [3, 4]], [[5, 6], [7, 8], [9, 10]]]),
    ("ç", "tst_UPV_W45", "tst_UPV_W45-01", 23, [[[0, 0], [5, 5]]]),
    (
        ";",
        "tst_UPV_W45",
        "tst_UPV_W45-02",
        27,
        [
            [[541, 1001], [541, 1001], [540, 987], [540, 987], [530, 977]] + [[530, 977]] * 4,
            SEMICOLON_STROKE_2,
        ],
    ),
    ("7", "tst_UPV_W45", "tst_UPV_W45-02", 32, [[[42, 43]]]),
]


def assert_fixture_samples(samples: list[RawSample]) -> None:
    assert len(samples) == len(EXPECTED)
    for sample, (char, writer, session, line, strokes) in zip(samples, EXPECTED, strict=True):
        assert (sample.char, sample.writer, sample.session, sample.line) == (
            char,
            writer,
            session,
            line,
        )
        assert sample.source == "uji"
        assert sample.num_strokes == len(strokes)
        for got, want in zip(sample.strokes, strokes, strict=True):
            assert got.shape == (len(want), 2)
            assert got.dtype == np.float64
            np.testing.assert_array_equal(got, np.array(want, dtype=np.float64))


def fixture_text() -> str:
    return FIXTURE.read_bytes().decode("utf-8")


def test_fixture_really_has_crlf_and_utf8() -> None:
    data = FIXTURE.read_bytes()
    assert data.count(b"\r\n") == data.count(b"\n") > 30
    assert "ñ".encode() in data
    assert "ç".encode() in data
    assert b"\t" in data


def test_read_uji_parses_fixture_exactly() -> None:
    assert_fixture_samples(read_uji(FIXTURE))


@pytest.mark.parametrize("newline", ["\n", "\r", "\r\n"])
def test_line_ends_do_not_matter(tmp_path: Path, newline: str) -> None:
    path = tmp_path / "uji.txt"
    text = fixture_text().replace("\r\n", "\n").replace("\n", newline)
    path.write_bytes(text.encode("utf-8"))
    assert_fixture_samples(read_uji(path))


def test_bom_and_latin1_fallback(tmp_path: Path) -> None:
    bom = tmp_path / "bom.txt"
    bom.write_bytes(b"\xef\xbb\xbf" + FIXTURE.read_bytes())
    assert_fixture_samples(read_uji(bom))
    latin = tmp_path / "latin1.txt"
    latin.write_bytes(fixture_text().encode("latin-1"))
    samples = read_uji(latin)
    assert_fixture_samples(samples)
    assert [s.char for s in samples][2:4] == ["ñ", "ç"]


def test_parse_uji_accepts_whole_text_and_lines() -> None:
    text = fixture_text()
    assert_fixture_samples(parse_uji(text))
    assert_fixture_samples(parse_uji(text.splitlines(keepends=True)))


def test_read_uji_reads_zip_archive(tmp_path: Path) -> None:
    archive = tmp_path / "uji.zip"
    with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as zipped:
        zipped.writestr("uji2.names", "description")
        zipped.writestr("ujipenchars2.txt", FIXTURE.read_bytes())
    assert_fixture_samples(read_uji(archive))


def test_zip_without_data_and_unreadable_paths(tmp_path: Path) -> None:
    archive = tmp_path / "other.zip"
    with zipfile.ZipFile(archive, "w") as zipped:
        zipped.writestr("a.csv", "x")
        zipped.writestr("b.csv", "y")
    with pytest.raises(UsageError, match=r"other\.zip holds no ujipenchars2\.txt"):
        read_uji(archive)
    with pytest.raises(UsageError, match=r"cannot read UJI file .*missing\.txt"):
        read_uji(tmp_path / "missing.txt")


def test_errors_name_the_member_inside_a_zip(tmp_path: Path) -> None:
    archive = tmp_path / "bad.zip"
    with zipfile.ZipFile(archive, "w") as zipped:
        zipped.writestr("ujipenchars2.txt", "WORD a x-01\nNUMSTROKES 1\nPOINTS 2 # 1 2\n")
    with pytest.raises(DataFormatError, match=r"bad\.zip:ujipenchars2\.txt, line 3: "):
        read_uji(archive)


GOOD = "WORD a trn_UJI_W01-01\nNUMSTROKES 1\nPOINTS 2 # 1 2 3 4\n"


MALFORMED = {
    "count_mismatch": (
        GOOD + "WORD b s-01\nNUMSTROKES 1\nPOINTS 3 # 1 2 3 4\n",
        6,
        "POINTS count is 3 but the line has 2 coordinate pairs",
    ),
    "odd_coordinates": (
        "WORD a s-01\nNUMSTROKES 1\nPOINTS 2 # 1 2 3\n",
        3,
        "odd number of coordinates",
    ),
    "non_numeric": (
        "WORD a s-01\nNUMSTROKES 1\n\nPOINTS 2 # 1 2 3 x4\n",
        4,
        "coordinate 'x4' is not an integer",
    ),
    "float_coordinate": (
        "WORD a s-01\nNUMSTROKES 1\nPOINTS 1 # 1.5 2\n",
        3,
        "coordinate '1.5' is not an integer",
    ),
    "too_few_before_word": (
        "WORD a s-01\nNUMSTROKES 2\nPOINTS 1 # 1 2\n// c\nWORD b s-01\nNUMSTROKES 1\nPOINTS 1 # 1 2\n",
        2,
        "NUMSTROKES 2 but only 1 POINTS lines follow before line 5",
    ),
    "too_few_before_eof": (
        GOOD + "WORD b s-01\n  NUMSTROKES 3\nPOINTS 1 # 1 2\n\n",
        5,
        "before the end of the file",
    ),
    "too_many": (
        "WORD a s-01\nNUMSTROKES 1\nPOINTS 1 # 1 2\nPOINTS 1 # 3 4\n",
        4,
        "more POINTS lines than NUMSTROKES 1",
    ),
    "points_outside_entry": ("// header\nPOINTS 1 # 1 2\n" + GOOD, 2, "POINTS outside an entry"),
    "numstrokes_outside_entry": ("NUMSTROKES 1\n" + GOOD, 1, "NUMSTROKES outside an entry"),
    "missing_numstrokes_then_points": (
        "WORD a s-01\nPOINTS 1 # 1 2\n",
        2,
        "POINTS line before NUMSTROKES",
    ),
    "missing_numstrokes_then_word": (
        "WORD a s-01\n" + GOOD,
        1,
        "has no NUMSTROKES line before line 2",
    ),
    "missing_numstrokes_at_eof": (
        GOOD + "\nWORD b s-01\n",
        5,
        "has no NUMSTROKES line before the end",
    ),
    "second_numstrokes": ("WORD a s-01\nNUMSTROKES 1\nNUMSTROKES 1\n", 3, "second NUMSTROKES"),
    "unknown_keyword": (GOOD + "  STROKES 1\n", 4, "unknown line starting with 'STROKES'"),
    "points_zero": (
        "WORD a s-01\nNUMSTROKES 1\nPOINTS 0 #\n",
        3,
        "POINTS count must be a positive integer, got 0",
    ),
    "numstrokes_zero": (
        "WORD a s-01\nNUMSTROKES 0\n",
        2,
        "NUMSTROKES must be a positive integer, got 0",
    ),
    "numstrokes_text": (
        "WORD a s-01\nNUMSTROKES two\n",
        2,
        "NUMSTROKES must be a positive integer, got 'two'",
    ),
    "no_hash": ("WORD a s-01\nNUMSTROKES 1\nPOINTS 1 1 2\n", 3, "no '#'"),
    "word_without_session": (GOOD + "WORD b\n", 4, "WORD line needs a character and a session id"),
}


@pytest.mark.parametrize("name", sorted(MALFORMED))
def test_malformed_input_names_path_and_line(tmp_path: Path, name: str) -> None:
    text, line, message = MALFORMED[name]
    path = tmp_path / f"{name}.txt"
    path.write_bytes(text.replace("\n", "\r\n").encode("utf-8"))
    with pytest.raises(DataFormatError, match=rf"{name}\.txt, line {line}: .*") as info:
        read_uji(path)
    assert message in str(info.value)
    assert info.value.line == line


@pytest.mark.parametrize("text", ["", "\r\n\r\n", "// only\n  // comments\n", "\ufeff"])
def test_file_without_entries_is_a_usage_error(tmp_path: Path, text: str) -> None:
    path = tmp_path / "empty.txt"
    path.write_bytes(text.encode("utf-8"))
    with pytest.raises(
        UsageError, match=r"no samples found in .*empty\.txt: .*WORD/NUMSTROKES/POINTS"
    ):
        read_uji(path)


@pytest.mark.parametrize(
    ("session", "writer"),
    [
        ("trn_UJI_W01-01", "trn_UJI_W01"),
        ("trn_UJI_W01-02", "trn_UJI_W01"),
        ("tst_UPV_W60-02", "tst_UPV_W60"),
        ("writer-7-12", "writer-7"),
        ("plain", "plain"),
        ("W03-", "W03-"),
        ("-01", "-01"),
    ],
)
def test_writer_from_session(session: str, writer: str) -> None:
    assert writer_from_session(session) == writer


def test_select_single_stroke_alphabet() -> None:
    samples = read_uji(FIXTURE)
    two_strokes = RawSample("x", "w", "w-01", [np.zeros((2, 2)), np.ones((3, 2))], "uji")
    kept, counts = select_single_stroke_alphabet([*samples, two_strokes])
    assert [s.char for s in kept] == ["a", "A", "7"]
    assert counts == {
        "total": 7,
        "kept": 3,
        "dropped_not_in_alphabet": 3,  # ñ, ç, ;
        "dropped_multi_stroke": 1,  # x
    }


def synthetic_uji(entries: int, seed: int = 0) -> str:
    """Text in the UJI format of the real file's size (1-3 strokes of 20-80 points each)."""
    rng = np.random.default_rng(seed)
    pool = []  # distinct POINTS lines, reused to keep generation quick
    for _ in range(256):
        k = int(rng.integers(20, 80))
        coords = " ".join(map(str, rng.integers(-50, 2000, size=2 * k)))
        pool.append(f"  POINTS {k} # {coords}")
    out = ["// UJI: 100 units per millimetre"]
    for i in range(entries):
        char = "abc"[i % 3]
        strokes = 1 + i % 3
        out.append(f"// ASCII char: {char}")
        out.append(f"WORD {char} trn_UJI_W{i % 60 + 1:02d}-{i % 2 + 1:02d}")
        out.append(f"  NUMSTROKES {strokes}")
        out.extend(pool[(i + j) % len(pool)] for j in range(strokes))
    return "\r\n".join(out) + "\r\n"


def test_full_size_file_parses_fast(tmp_path: Path) -> None:
    path = tmp_path / "ujipenchars2.txt"
    path.write_bytes(synthetic_uji(11_640).encode("utf-8"))
    start = time.perf_counter()
    samples = read_uji(path)
    elapsed = time.perf_counter() - start
    assert len(samples) == 11_640
    assert len({s.writer for s in samples}) == 60
    assert elapsed < 3.0, f"parsing took {elapsed:.2f} s"
