"""Tests of ``prg.data.synthetic``."""

import numpy as np
import pytest

from prg.alphabet import ALPHABET
from prg.data.synthetic import SyntheticSettings, generate, join_strokes, writer_styles
from prg.errors import UsageError


def test_shape_mirrors_uji_writers_sessions_characters():
    cfg = SyntheticSettings(n_writers=5, samples_per_char=2)
    samples = generate(cfg)
    assert len(samples) == 5 * 2 * 62
    assert {s.char for s in samples} == set(ALPHABET)
    assert len({s.writer for s in samples}) == 5
    assert all(s.num_strokes == 1 and s.source == "synthetic" for s in samples)
    per_writer_char = {(s.writer, s.char) for s in samples}
    assert len(per_writer_char) == 5 * 62  # each writer wrote each character twice


def test_deterministic_for_a_seed_and_different_for_another():
    a = generate(SyntheticSettings(n_writers=2, seed=3))
    b = generate(SyntheticSettings(n_writers=2, seed=3))
    c = generate(SyntheticSettings(n_writers=2, seed=4))
    assert all(np.array_equal(x.strokes[0], y.strokes[0]) for x, y in zip(a, b))
    assert not all(np.array_equal(x.strokes[0], y.strokes[0]) for x, y in zip(a, c))


def test_writers_have_distinct_styles_and_fonts_rotate():
    styles = writer_styles(SyntheticSettings(n_writers=8))
    assert [s.font for s in styles[:4]] == ["futural", "rowmans", "scripts", "cursive"]
    assert len({round(s.slant, 6) for s in styles}) == 8


def test_two_sessions_of_a_writer_differ_less_than_two_writers():
    from prg.data.preprocess import preprocess_stroke

    samples = generate(SyntheticSettings(n_writers=8, characters="a"))
    traj = {(s.writer, s.session[-1]): preprocess_stroke(s.strokes[0]) for s in samples}
    same = [np.abs(traj[(w, "1")] - traj[(w, "2")]).mean() for w in {k[0] for k in traj}]
    # writers 1 and 5 share a font (futural), so the comparison isolates the personal style
    other = np.abs(traj[("SYN_W01", "1")] - traj[("SYN_W05", "1")]).mean()
    assert np.median(same) < other


def test_join_drops_dots_and_prefers_short_pen_travel():
    stem = np.array([[0.0, 0], [0, 10]])
    dot = np.array([[0.0, -3], [0.2, -3]])
    joined = join_strokes([stem, dot])
    assert len(joined) == 2  # the dot is gone
    # a "Z" given as diagonal, top bar, bottom bar: the greedy order writes top, diagonal, bottom
    top = np.array([[0.0, 0], [10, 0]])
    diagonal = np.array([[10.0, 0], [0, 10]])
    bottom = np.array([[0.0, 10], [10, 10]])
    z = join_strokes([diagonal, top, bottom])
    np.testing.assert_allclose(z[0], [0, 0])
    np.testing.assert_allclose(z[-1], [10, 10])
    assert len(z) == 6


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"n_writers": 0}, "n_writers"),
        ({"samples_per_char": 0}, "samples_per_char"),
        ({"fonts": ("comic",)}, "fonts"),
        ({"slant": (0.5, 0.1)}, "min > max"),
    ],
)
def test_bad_settings_are_named(kwargs, match):
    with pytest.raises(UsageError, match=match):
        SyntheticSettings(**kwargs)
