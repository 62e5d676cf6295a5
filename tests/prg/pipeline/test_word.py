"""The word trajectory: assembly, JSON round trip, SVG and PNG renderings."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from PIL import Image

from prg.errors import UsageError
from prg.pipeline.connect import ConnectionSettings, connect_sequence
from prg.pipeline.dmp import DMP
from prg.pipeline.word import (
    SCHEMA_VERSION,
    WordTrajectory,
    _atomic_write,
    assemble_word,
    dash_pieces,
)
from tests.helpers.word import letters_cm, word  # noqa: F401 (fixtures)

DELTA = ConnectionSettings().delta


def test_segments_alternate_letters_connections_and_the_pen_up_space(word):
    assert word.segment_kinds == [
        "letter",
        "connection",
        "letter",
        "space",
        "letter",
        "connection",
        "letter",
    ]
    assert np.all(np.diff(word.segment) >= 0)
    space = word.segment_kinds.index("space")
    assert not word.pen_down()[word.segment == space].any()
    assert word.pen_down()[word.segment != space].all()


def test_joins_between_letters_leave_no_gap_larger_than_delta(word):
    gaps = np.hypot(*np.diff(word.points, axis=0).T)
    kinds = np.array(word.segment_kinds)[word.segment]
    # every step into, inside or out of a connection or space segment
    touches = (kinds[:-1] != "letter") | (kinds[1:] != "letter")
    assert touches.sum() > 0
    assert gaps[touches].max() <= DELTA * (1 + 1e-9)


def test_duration_is_the_path_length_at_the_writing_speed(word):
    assert word.duration_s == pytest.approx(word.path_length / 2.5)


def test_json_round_trip_is_exact(word, tmp_path):
    path = word.to_json(tmp_path / "word.json")
    back = WordTrajectory.from_json(path)
    np.testing.assert_array_equal(back.points, word.points)
    np.testing.assert_array_equal(back.segment, word.segment)
    assert back.segment_kinds == word.segment_kinds
    assert back.text == word.text
    assert isinstance(back.dmp, DMP) and back.dmp.to_dict() == word.dmp.to_dict()
    assert (back.speed_cm_s, back.duration_s) == (word.speed_cm_s, word.duration_s)
    assert json.loads(path.read_text())["version"] == SCHEMA_VERSION == 2


def test_the_dmp_is_stored_as_its_to_dict_and_rewritten_byte_for_byte(word, tmp_path):
    path = word.to_json(tmp_path / "w.json")
    assert json.loads(path.read_text())["dmp"] == word.dmp.to_dict()
    back = WordTrajectory.from_json(path)
    assert back.to_json(tmp_path / "again.json").read_bytes() == path.read_bytes()
    no_dmp = assemble_word(letters_cm("ab"), connect_sequence(letters_cm("ab")), "ab")
    assert json.loads(no_dmp.to_json(tmp_path / "plain.json").read_text())["dmp"] is None


def test_a_word_holds_a_dmp_object_not_its_dict(word):
    with pytest.raises(UsageError, match="dmp must be a DMP or None, got dict"):
        WordTrajectory(
            word.points, word.segment, word.segment_kinds, word.text, dmp=word.dmp.to_dict()
        )


def test_writing_leaves_no_temporary_files(word, tmp_path):
    word.to_json(tmp_path / "w.json")
    word.to_svg(tmp_path / "w.svg")
    word.to_png(tmp_path / "w.png", dpi=40)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["w.json", "w.png", "w.svg"]


def test_a_failed_write_keeps_the_old_file(tmp_path):
    target = tmp_path / "w.json"
    target.write_text("old")

    def half_then_fail(tmp):
        tmp.write_text("half")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError):
        _atomic_write(target, half_then_fail)
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["w.json"]


@pytest.mark.parametrize(
    ("content", "match"),
    [
        ('{"schema": "prg.word_trajectory", "vers', "not valid JSON"),
        ("[1, 2]", "expected a JSON object"),
        ('{"schema": "other", "version": 1}', "schema must be"),
        ('{"schema": "prg.word_trajectory", "version": 7}', "unsupported version 7"),
        ('{"schema": "prg.word_trajectory", "version": 1, "text": "a"}', "missing field"),
    ],
)
def test_corrupt_json_is_a_one_line_usage_error_naming_the_file(tmp_path, content, match):
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(UsageError, match=match) as err:
        WordTrajectory.from_json(path)
    assert str(path) in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("points", [[0.0, 1.0]], "segment must have shape"),
        ("segment_kinds", ["letter"], "segment_kinds has 1 entries"),
        (
            "segment_kinds",
            ["letter", "ink", "letter", "space", "letter", "connection", "letter"],
            "unknown segment kind 'ink'",
        ),
        ("text", "abc", "has 3 characters but there are 4 letter segments"),
        ("speed_cm_s", -1.0, "speed_cm_s must be a positive"),
        ("dmp", [1, 2], "dmp must be a dict"),
        ("dmp", {"tau": 1.0}, r"invalid DMP \(DMP data: missing keys"),
    ],
)
def test_inconsistent_documents_are_refused(word, tmp_path, field, value, match):
    doc = word.to_dict()
    doc[field] = value
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(UsageError, match=match):
        WordTrajectory.from_json(path)


def test_a_missing_file_is_named(tmp_path):
    with pytest.raises(UsageError, match="no such word trajectory file"):
        WordTrajectory.from_json(tmp_path / "absent.json")


def test_segment_ids_must_run_in_order(word):
    with pytest.raises(UsageError, match="segment ids must run"):
        WordTrajectory(word.points, word.segment[::-1], word.segment_kinds, word.text)


def test_assembly_checks_its_counts():
    placed = letters_cm("ab")
    with pytest.raises(UsageError, match="2 letters need 1 connections, got 0"):
        assemble_word(placed, [], "ab")
    with pytest.raises(UsageError, match="has 3 characters but 2 letter trajectories"):
        assemble_word(placed, [np.zeros((0, 2))], "abc")


def test_touching_letters_get_no_connection_segment():
    placed = letters_cm("ab")
    w = assemble_word(placed, [np.zeros((0, 2))], "ab")
    assert w.segment_kinds == ["letter", "letter"]


def svg_polylines(path) -> list[ET.Element]:
    root = ET.parse(path).getroot()
    return root.findall("{http://www.w3.org/2000/svg}polyline")


def test_svg_draws_letters_and_connections_in_distinct_styles(word, tmp_path):
    lines = svg_polylines(word.to_svg(tmp_path / "w.svg"))
    styles = {}
    for line in lines:
        styles.setdefault(line.get("class"), set()).add(
            (line.get("stroke"), line.get("stroke-dasharray"))
        )
    assert sorted(styles) == ["connection", "letter", "space"]
    assert all(len(s) == 1 for s in styles.values())
    assert len({next(iter(s)) for s in styles.values()}) == 3
    assert sum(line.get("class") == "letter" for line in lines) == 4


def test_plain_svg_is_all_black_ink_without_pen_up_travel(word, tmp_path):
    lines = svg_polylines(word.to_svg(tmp_path / "w.svg", highlight=False))
    assert {line.get("stroke") for line in lines} == {"#000000"}
    assert "space" not in {line.get("class") for line in lines}


def test_png_opens_and_shows_connections_only_when_highlighted(word, tmp_path):
    def reddish_pixels(path) -> int:
        with Image.open(path) as img:
            rgb = np.asarray(img.convert("RGB")).astype(int)
        return int(((rgb[..., 0] > 150) & (rgb[..., 1] < 100) & (rgb[..., 2] < 100)).sum())

    highlighted = word.to_png(tmp_path / "h.png", dpi=60)
    plain = word.to_png(tmp_path / "p.png", dpi=60, highlight=False)
    with Image.open(highlighted) as img:
        assert img.format == "PNG" and img.width > img.height > 10
    assert reddish_pixels(highlighted) > 0
    assert reddish_pixels(plain) == 0


def test_the_png_is_true_to_scale_with_the_ink_where_the_points_are(word, tmp_path):
    dpi = 100
    with Image.open(word.to_png(tmp_path / "w.png", dpi=dpi, highlight=False)) as img:
        dark = np.asarray(img.convert("L")) < 128
        assert img.info["dpi"] == pytest.approx((dpi, dpi), rel=1e-4)  # stored per metre
    extent_cm = np.ptp(word.points, axis=0) + 0.6  # the 0.3 cm margin on each side
    assert dark.shape[::-1] == tuple(np.ceil(extent_cm / 2.54 * dpi).astype(int))
    rows, cols = np.nonzero(dark)
    px_per_cm = dpi / 2.54
    for got, extent in zip((np.ptp(cols), np.ptp(rows)), np.ptp(word.points, axis=0)):
        assert got / px_per_cm == pytest.approx(extent, abs=0.1)  # within a pen width or two
    # every drawn point is inked (a 3x3 neighbourhood: the pen is about 1.6 px wide at 100 dpi)
    lo = word.points.min(axis=0) - 0.3
    x = np.rint((word.points[:, 0] - lo[0]) * px_per_cm).astype(int)
    y = np.rint((word.points.max(axis=0)[1] + 0.3 - word.points[:, 1]) * px_per_cm).astype(int)
    padded = np.pad(dark, 1)
    near = np.zeros(len(x), bool)
    for dx in (0, 1, 2):
        for dy in (0, 1, 2):
            near |= padded[y + dy, x + dx]
    pen_down = ~np.isin(np.asarray(word.segment_kinds)[word.segment], ["space", "lift"])
    assert near[pen_down].all() and pen_down.sum() > 100


@pytest.mark.parametrize("pattern", [(3.0, 3.0), (1.0, 3.0), (2.0, 1.0, 0.5, 1.0)])
def test_dashes_cover_their_share_of_the_line_and_stay_on_it(pattern):
    rng = np.random.default_rng(1)
    points = np.cumsum(rng.normal(0, 1, (40, 2)), axis=0)
    steps = np.hypot(*np.diff(points, axis=0).T)
    pieces = dash_pieces(points, pattern)
    lengths = [np.hypot(*np.diff(p, axis=0).T).sum() for p in pieces]
    period, on = sum(pattern), sum(pattern[0::2])
    assert max(lengths) <= max(pattern[0::2]) + 1e-9
    assert sum(lengths) == pytest.approx(steps.sum() * on / period, abs=period)
    # each dash's ends lie on the polyline (distance to its nearest segment)
    for piece in pieces:
        for end in (piece[0], piece[-1]):
            a, b = points[:-1], points[1:]
            t = np.clip(((end - a) * (b - a)).sum(1) / np.maximum((steps**2), 1e-12), 0, 1)
            assert np.min(np.hypot(*(a + t[:, None] * (b - a) - end).T)) < 1e-9
