"""Connection strokes between letters: Algorithm 1's guarantees and the straight joiner."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from prg.checks import check_values
from prg.data.preprocess import (
    normalise,
    resample_arclength,
)
from prg.errors import SettingsError, UsageError
from prg.pipeline.connect import (
    ConnectionSettings,
    connect_letters,
    connect_sequence,
    connection_path,
    straight_connection,
    subdivide,
)
from tests.conftest import letter_like
from tests.helpers.joins import _arc
from tests.helpers.properties import examples, log_uniform, steps

P = ConnectionSettings()


EPS = 1e-9


def random_pair(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Two random smooth 'letters' 0.75-1.5 cm tall, the second to the right of the first."""

    def letter() -> np.ndarray:
        pts = normalise(resample_arclength(letter_like(rng, 80), 100))
        return pts * rng.uniform(0.35, 0.75)

    prev, nxt = letter(), letter()
    shift = np.array([prev[:, 0].max() - nxt[:, 0].min() + rng.uniform(0.05, 0.6), 0.0])
    nxt = nxt + shift + [0.0, rng.normal(0, 0.3)]
    return prev, nxt


PAIRS = [random_pair(np.random.default_rng(seed)) for seed in range(40)]


def cross2(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def step_lengths(path: np.ndarray) -> np.ndarray:
    d = np.diff(path, axis=0)
    return np.hypot(d[:, 0], d[:, 1])


def heading_changes(prev: np.ndarray, nxt: np.ndarray, steered: np.ndarray) -> np.ndarray:
    """|turn| between consecutive segments of [prev's last moving segment, steered steps...]."""
    d = np.diff(prev, axis=0)
    moving = d[np.hypot(d[:, 0], d[:, 1]) > 1e-12]
    first = moving[-1] if len(moving) else nxt[0] - prev[-1]
    steps = np.diff(np.concatenate([prev[-1:], steered]), axis=0)
    vecs = np.concatenate([first[None], steps])
    angles = np.arctan2(vecs[:, 1], vecs[:, 0])
    return np.abs(np.remainder(np.diff(angles) + np.pi, 2 * np.pi) - np.pi)


def check_guarantees(prev, nxt, result, delta, alpha_max, max_steps) -> None:
    path = connection_path(prev, result, nxt)
    assert np.all(np.isfinite(path))
    assert step_lengths(path).max(initial=0.0) <= delta * (1 + EPS)
    assert 0 <= result.steered <= min(max_steps, len(result.points))
    steered = result.points[: result.steered]
    if result.steered:
        np.testing.assert_allclose(step_lengths(np.concatenate([prev[-1:], steered])), delta)
        assert heading_changes(prev, nxt, steered).max() <= alpha_max + 1e-9
    if not result.fallback:
        end = result.points[-1] if len(result.points) else prev[-1]
        assert np.hypot(*(nxt[0] - end)) <= delta * (1 + EPS)


@pytest.mark.parametrize("join", ["first", "retrace"])
def test_connections_of_random_letter_pairs_keep_every_guarantee(join):
    for prev, nxt in PAIRS:
        result = connect_letters(prev, nxt, join=join)
        check_guarantees(prev, nxt, result, P.delta, P.alpha_max, P.max_steps)


def test_default_connections_of_random_letter_pairs_need_no_fallback():
    results = [connect_letters(prev, nxt) for prev, nxt in PAIRS]
    assert not any(r.fallback for r in results)
    assert all(r.target == 0 for r in results)


def test_connection_turns_smoothly_where_the_straight_joiner_kinks():
    # prev ends heading down; next letter starts up and to the right: a U-turn is needed
    prev = np.column_stack([np.zeros(20), np.linspace(1.0, 0.0, 20)])
    nxt = np.column_stack([np.linspace(0.8, 1.2, 20), np.full(20, 0.8)])
    result = connect_letters(prev, nxt)
    assert not result.fallback
    assert heading_changes(prev, nxt, result.points[: result.steered]).max() <= P.alpha_max + EPS
    straight = straight_connection(prev, nxt)
    kink = heading_changes(prev, nxt, np.concatenate([straight.points, nxt[:1]]))[0]
    assert kink > math.radians(120)


def test_target_inside_the_turning_circle_is_reached_not_orbited():
    # the next letter starts just left of the pen, inside its tightest left turn
    prev = np.column_stack([np.linspace(-1.0, 0.0, 20), np.zeros(20)])
    nxt = np.array([[0.0, 0.12], [-0.2, 0.3], [-0.4, 0.5]])
    result = connect_letters(prev, nxt)
    assert not result.fallback
    check_guarantees(prev, nxt, result, P.delta, P.alpha_max, P.max_steps)


@pytest.mark.parametrize(  # radii 0.16, 0.15 and 3.2 (a circle wider than 1: no unit hides)
    ("delta", "alpha_deg"), [(P.delta, math.degrees(P.alpha_max)), (0.08, 30.0), (1.0, 18.0)]
)
def test_every_target_inside_either_turning_circle_is_reached_the_same_way_by_both_branches(
    delta, alpha_deg
):
    """Targets all over the pen's two tightest turning circles (radius delta / (2 sin(alpha/2)),
    centred a radius to the left and to the right of the pen heading east) are reached by
    steering, never by the straight fallback; and the homing branch (scalars, the first point
    alone) takes the very steps the candidate branch takes when the first point is the only
    candidate."""
    alpha = math.radians(alpha_deg)
    radius = delta / (2 * math.sin(alpha / 2))
    prev = np.column_stack([np.linspace(-1.0, 0.0, 30), np.zeros(30)])
    reached = 0
    for side in (1.0, -1.0):
        for rho in (0.3, 0.6, 0.9, 0.97):
            for phi in np.linspace(0.0, 2 * np.pi, 12, endpoint=False):
                first = np.array(
                    [rho * radius * math.cos(phi), side * radius * (1 + rho * math.sin(phi))]
                )
                if np.hypot(*first) <= delta:
                    continue  # already joined: nothing to steer
                nxt = first[None, :]
                kw = {"delta": delta, "alpha_max": alpha, "max_steps": 400}
                steering = connect_letters(prev, nxt, home_radius=0.0, **kw)
                homing = connect_letters(prev, nxt, home_radius=10.0, **kw)
                assert not steering.fallback and not homing.fallback, (side, rho, phi)
                check_guarantees(prev, nxt, steering, delta, alpha, 400)
                assert steering.steered == homing.steered
                np.testing.assert_allclose(homing.points, steering.points, atol=1e-9)
                reached += 1
    assert reached > 80


def test_retrace_joins_inside_the_letter_and_runs_back_to_its_first_point():
    # a vertical stroke written top-down; the pen arrives from the left at its middle
    prev = np.column_stack([np.linspace(-1.0, 0.0, 20), np.zeros(20)])
    nxt = np.column_stack([np.full(41, 0.5), np.linspace(1.0, -1.0, 41)])
    result = connect_letters(prev, nxt, join="retrace", home_radius=0.0, theta_f=0.0, theta_p=4.0)
    assert 0 < result.target < 40 and result.fallback is False
    back = result.points[result.steered :]
    np.testing.assert_allclose(back[:, 0], 0.5)  # the return runs on the letter itself ...
    assert np.all(np.diff(back[:, 1]) > 0)  # ... upwards to its first point, never repeating one
    # the return passes through nxt[target], ..., nxt[1] in that order
    hits = [
        int(np.flatnonzero(np.all(np.isclose(back, nxt[k]), axis=1))[0])
        for k in range(result.target, 0, -1)
    ]
    assert hits == sorted(hits)
    check_guarantees(prev, nxt, result, P.delta, P.alpha_max, P.max_steps)


def test_first_join_never_joins_inside_the_letter():
    prev = np.column_stack([np.linspace(-1.0, 0.0, 20), np.zeros(20)])
    nxt = np.column_stack([np.full(41, 0.5), np.linspace(1.0, -1.0, 41)])
    result = connect_letters(prev, nxt, home_radius=0.0, theta_f=0.0, theta_p=4.0)
    assert result.target == 0 and not result.fallback
    assert np.hypot(*(result.points[-1] - nxt[0])) <= P.delta


def test_running_out_of_steps_finishes_with_a_straight_segment():
    prev, nxt = PAIRS[0]
    nxt = nxt + np.array([3.0, 0.0])  # far away: 3 steps cannot get there
    result = connect_letters(prev, nxt, max_steps=3)
    assert result.fallback and result.steered <= 3
    check_guarantees(prev, nxt, result, P.delta, P.alpha_max, 3)
    tail = np.concatenate([result.points[result.steered - 1 :], nxt[:1]])
    cross = cross2(tail[1:] - tail[0], nxt[0] - tail[0])  # collinear with the end
    np.testing.assert_allclose(cross, 0.0, atol=1e-9)


def test_zero_steps_is_the_straight_joiner():
    prev, nxt = PAIRS[1]
    result = connect_letters(prev, nxt, max_steps=0)
    assert result.fallback and result.steered == 0
    np.testing.assert_allclose(result.points, straight_connection(prev, nxt).points)


@pytest.mark.parametrize("offset", [(0.0, 0.0), (-3.0, 2.5), (4.0, -1.5)])
def test_letters_already_within_delta_need_no_connection(offset):
    """Wherever on the page the pair lies (the distance, not the coordinates, decides)."""
    prev = np.array([[0.0, 0.0], [1.0, 0.0]]) + offset
    nxt = np.array([[1.03, 0.02], [2.0, 0.0]]) + offset
    result = connect_letters(prev, nxt)
    assert result.points.shape == (0, 2) and result.steered == 0 and not result.fallback


def test_defaults_are_those_of_connection_params():
    prev, nxt = PAIRS[2]
    a = connect_letters(prev, nxt)
    b = connect_letters(prev, nxt, **ConnectionSettings().as_kwargs())
    np.testing.assert_array_equal(a.points, b.points)


def test_connect_letters_is_deterministic():
    prev, nxt = PAIRS[3]
    np.testing.assert_array_equal(
        connect_letters(prev, nxt).points, connect_letters(prev, nxt).points
    )


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"prev": np.zeros((3, 3))}, "prev must have shape"),
        ({"nxt": np.zeros((0, 2))}, "nxt must have shape"),
        ({"prev": np.array([[0.0, np.nan]])}, "prev contains NaN"),
        ({"delta": 0.0}, r"delta must be a finite number in \(0, 10\]"),
        ({"alpha_max": 4.0}, "alpha_max must be in"),
        ({"theta_a": -1.0}, r"theta_a must be a finite number in \[0, "),
        ({"home_radius": math.inf}, "home_radius must be"),
        ({"max_steps": 2.5}, r"max_steps must be an integer in \[0, 100,000\]"),
        ({"home_radius": -0.1}, r"home_radius must be a finite number in \[0, 100\]"),
        ({"join": "middle"}, "join must be one of"),
    ],
)
def test_bad_arguments_are_named(kwargs, match):
    args = {"prev": np.array([[0.0, 0.0], [1.0, 0.0]]), "nxt": np.array([[2.0, 0.0]]), **kwargs}
    with pytest.raises(UsageError, match=match):
        connect_letters(**args)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"delta": 0.0}, "delta"),
        ({"alpha_max": 4.0}, "alpha_max"),
        ({"theta_p": -1.0}, "theta_p"),
        ({"max_steps": -1}, "max_steps"),
        ({"join": "middle"}, "join"),
        ({"home_radius": "far"}, "home_radius"),
    ],
)
def test_connection_settings_refuse_bad_values_naming_the_field(kwargs, field):
    with pytest.raises(SettingsError) as caught:
        ConnectionSettings(**kwargs)
    assert caught.value.field == field


def test_connection_settings_hold_floats_and_an_integer_step_count():
    params = ConnectionSettings(delta=1, theta_f=4, max_steps=10)
    assert type(params.delta) is float and type(params.theta_f) is float
    assert type(params.max_steps) is int and params.max_steps == 10


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("max_steps", -1, "an integer in [0, 100,000], got -1"),
        ("max_steps", 10.0, "an integer in [0, 100,000], got 10.0"),
        ("home_radius", -0.5, "a finite number in [0, 100], got -0.5"),
        ("delta", 11.0, "a finite number in (0, 10], got 11.0"),
        ("theta_a", 2e6, "a finite number in [0, 1,000,000], got 2000000.0"),
    ],
)
def test_connection_settings_refuse_what_the_config_refuses(field, value, message):
    with pytest.raises(SettingsError) as in_class:
        ConnectionSettings(**{field: value})
    assert str(in_class.value) == f"{field} must be {message}"
    with pytest.raises(UsageError) as in_config:
        check_values({"connection": {field: value}})
    assert str(in_config.value) == f"connection.{field} must be {message}"


def test_alpha_max_takes_the_range_of_the_configs_degrees():
    assert ConnectionSettings(alpha_max=math.pi).alpha_max == math.pi  # 180 degrees
    check_values({"connection": {"alpha_max_deg": 180.0}})
    for radians in (0.0, math.pi + 1e-9):
        with pytest.raises(SettingsError, match=r"^alpha_max must be in \(0, pi\] radians"):
            ConnectionSettings(alpha_max=radians)
        with pytest.raises(UsageError, match=r"^connection\.alpha_max_deg must be a finite number"):
            check_values({"connection": {"alpha_max_deg": math.degrees(radians)}})


def test_connect_letters_and_the_config_accept_the_same_values():
    # no homing and no steered steps: accepted by the function, the settings and the config
    prev, nxt = PAIRS[1]
    assert connect_letters(prev, nxt, home_radius=0.0, max_steps=0).fallback
    assert ConnectionSettings(home_radius=0.0, max_steps=0).max_steps == 0
    check_values({"connection": {"home_radius": 0.0, "max_steps": 0}})
    # ... and refuse the same: the function checks its arguments with ConnectionSettings
    for field, value in [("home_radius", -0.5), ("max_steps", 100_001), ("delta", 11.0)]:
        with pytest.raises(SettingsError) as in_function:
            connect_letters(prev, nxt, **{field: value})
        with pytest.raises(UsageError) as in_config:
            check_values({"connection": {field: value}})
        assert str(in_function.value.under("connection")) == str(in_config.value)


def test_straight_joiner_spaces_points_evenly_at_most_delta_apart():
    prev = np.array([[0.0, 0.0], [1.0, 1.0]])
    nxt = np.array([[4.0, 5.0], [5.0, 5.0]])  # 5 cm away
    result = straight_connection(prev, nxt, delta=0.3)
    path = connection_path(prev, result, nxt)
    gaps = step_lengths(path)
    assert len(result.points) == math.ceil(5.0 / 0.3) - 1
    np.testing.assert_allclose(gaps, 5.0 / math.ceil(5.0 / 0.3))
    np.testing.assert_allclose(cross2(path - path[0], nxt[0] - path[0]), 0.0, atol=1e-12)


@pytest.mark.parametrize(("dist", "delta"), [(0.3, 0.1), (1.0, 0.1), (0.7, 0.07), (0.05, 0.05)])
def test_subdivide_respects_delta_at_exact_multiples(dist, delta):
    pts = subdivide(np.zeros(2), np.array([dist, 0.0]), delta)
    path = np.concatenate([[[0.0, 0.0]], pts, [[dist, 0.0]]])
    assert step_lengths(path).max() <= delta * (1 + 1e-12)  # up to rounding of the coordinates
    assert len(pts) <= round(dist / delta)


def test_connect_sequence_uses_the_straight_pen_up_travel_across_word_breaks():
    letters = [PAIRS[4][0], PAIRS[4][1], PAIRS[4][1] + [2.5, 0.0]]
    results = connect_sequence(letters, breaks=[False, True])
    assert results[0].steered > 0
    np.testing.assert_allclose(
        results[1].points, straight_connection(letters[1], letters[2]).points
    )
    straight = connect_sequence(letters, method="straight")
    assert all(r.steered == 0 for r in straight)
    with pytest.raises(UsageError, match="breaks must have one entry per letter pair"):
        connect_sequence(letters, breaks=[True])


coords = st.floats(-4.0, 4.0, allow_nan=False, allow_infinity=False)


@settings(max_examples=60, deadline=None)
@given(
    prev=arrays(np.float64, st.tuples(st.integers(1, 6), st.just(2)), elements=coords),
    nxt=arrays(np.float64, st.tuples(st.integers(1, 30), st.just(2)), elements=coords),
    delta=st.floats(0.02, 0.5),
    alpha_max=st.floats(0.02, math.pi),
    thetas=st.tuples(*[st.floats(0.0, 5.0)] * 4),
    home_radius=st.floats(0.0, 2.0),
    max_steps=st.integers(0, 300),
    join=st.sampled_from(["first", "retrace"]),
)
def test_arbitrary_inputs_give_finite_gap_free_connections(
    prev, nxt, delta, alpha_max, thetas, home_radius, max_steps, join
):
    theta_o, theta_a, theta_f, theta_p = thetas
    result = connect_letters(
        prev,
        nxt,
        delta,
        alpha_max,
        theta_o,
        theta_a,
        theta_f,
        theta_p,
        home_radius=home_radius,
        max_steps=max_steps,
        join=join,
    )
    check_guarantees(prev, nxt, result, delta, alpha_max, max_steps)


# ---- non-default parameters: every steered step is the cheapest candidate ----------------------
# The guarantees above hold for any weights, so they cannot tell a weight that is ignored or
# swapped. Here each steered step is checked against the candidate competition of the module
# docstring, recomputed in the test: one candidate per target point (the heading turned towards
# it, clipped to alpha_max, one step of delta), cost theta_o j/m + theta_a A + theta_f F + theta_p P
# with min-max normalised A, F, P, only the first point once within home_radius. Steps where a
# target lies within two turning radii of the pen are skipped (the orbit rule may apply there).


def _minmax(v: np.ndarray) -> np.ndarray:
    span = v.max() - v.min()
    return (v - v.min()) / span if span > 1e-12 * max(1.0, abs(v.min())) else np.zeros_like(v)


def _check_steps_are_cheapest(prev, nxt, result, kw) -> int:
    delta, alpha = kw["delta"], kw["alpha_max"]
    radius = delta / (2 * math.sin(alpha / 2))
    steered = result.points[: result.steered]
    pens = np.concatenate([prev[-1:], steered])
    d = np.diff(prev, axis=0)
    first_dir = d[np.hypot(d[:, 0], d[:, 1]) > 1e-12][-1]
    checked = 0
    homing = False
    for i in range(result.steered):
        pen = pens[i]
        into = first_dir if i == 0 else pens[i] - pens[i - 1]
        heading = math.atan2(into[1], into[0])
        homing = homing or np.hypot(*(nxt[0] - pen)) < kw["home_radius"]
        targets = nxt[:1] if homing else nxt
        to = targets - pen
        if np.hypot(to[:, 0], to[:, 1]).min() <= 2 * radius:
            continue
        wanted = np.angle(np.exp(1j * (np.arctan2(to[:, 1], to[:, 0]) - heading)))
        turn = np.clip(wanted, -alpha, alpha)
        cand = pen + delta * np.column_stack([np.cos(heading + turn), np.sin(heading + turn)])
        m = len(nxt)
        cost = (
            kw["theta_o"] * np.arange(len(targets)) / m
            + kw["theta_a"] * _minmax(np.abs(turn))
            + kw["theta_f"] * _minmax(np.hypot(*(cand - nxt[0]).T))
            + kw["theta_p"] * _minmax(np.hypot(*(cand - targets).T))
        )
        cheapest = cand[cost <= cost.min() + 1e-9]
        assert np.hypot(*(cheapest - pens[i + 1]).T).min() < 1e-9, f"step {i}"
        checked += 1
    return checked


@pytest.mark.parametrize(
    "kw",
    [
        {"theta_o": 2.0, "theta_a": 0.3, "theta_f": 1.0, "theta_p": 3.0, "home_radius": 0.25},
        {"theta_o": 0.0, "theta_a": 2.5, "theta_f": 0.5, "theta_p": 0.0, "home_radius": 0.0},
        {"theta_o": 0.5, "theta_a": 0.0, "theta_f": 0.0, "theta_p": 1.0, "home_radius": 0.6},
        {"theta_o": 3.0, "theta_a": 0.0, "theta_f": 0.0, "theta_p": 0.0, "home_radius": 0.0},
    ],
    ids=["mixed", "turn-averse", "own-target", "index-only"],
)
@pytest.mark.parametrize(("delta", "alpha_deg"), [(0.04, 25.0), (0.08, 12.0)])
def test_each_steered_step_is_the_cheapest_candidate_for_non_default_weights(kw, delta, alpha_deg):
    kw = {**kw, "delta": delta, "alpha_max": math.radians(alpha_deg)}
    checked = 0
    for prev, nxt in PAIRS[:5]:
        result = connect_letters(prev, nxt, max_steps=80, **kw)
        check_guarantees(prev, nxt, result, delta, kw["alpha_max"], 80)
        checked += _check_steps_are_cheapest(prev, nxt, result, kw)
    assert checked > 30  # the check ran on many steps, not only on skipped ones


def _same_result(a, b) -> None:
    """Every field of two ConnectionResults."""
    np.testing.assert_array_equal(a.points, b.points)
    assert (a.steered, a.target, a.fallback) == (b.steered, b.target, b.fallback)


def test_connect_sequence_passes_non_default_params_to_both_joiners():
    params = ConnectionSettings(delta=0.03, alpha_max=math.radians(30), theta_f=2.0, theta_p=1.5)
    letters = [PAIRS[5][0], PAIRS[5][1], PAIRS[5][1] + [2.5, 0.0], PAIRS[6][0] + [5.0, 0.0]]
    results = connect_sequence(letters, params, breaks=[False, True, False])
    _same_result(results[0], connect_letters(letters[0], letters[1], **params.as_kwargs()))
    _same_result(results[1], straight_connection(letters[1], letters[2], params.delta))
    _same_result(results[2], connect_letters(letters[2], letters[3], **params.as_kwargs()))
    straight = connect_sequence(letters, params, method="straight")
    for r, a, b in zip(straight, letters[:-1], letters[1:]):
        _same_result(r, straight_connection(a, b, params.delta))
    # without breaks every pair is joined by Algorithm 1
    for r, a, b in zip(connect_sequence(letters, params), letters[:-1], letters[1:]):
        _same_result(r, connect_letters(a, b, **params.as_kwargs()))


def test_connect_sequence_of_one_letter_has_no_connections():
    assert connect_sequence([PAIRS[0][0]]) == []
    assert connect_sequence([PAIRS[0][0]], breaks=[]) == []
    assert connect_sequence([]) == []


def test_straight_joiner_result_fields_and_bad_arguments():
    result = straight_connection([[0.0, 0.0]], [[1.0, 0.0]], delta=0.3)
    assert (result.steered, result.target, result.fallback) == (0, 0, False)
    assert isinstance(result.fallback, bool) and isinstance(result.target, int)
    for kwargs, match in [
        ({"prev": np.zeros((2, 3))}, "prev must have shape"),
        ({"nxt": [[np.inf, 0.0]]}, "nxt contains NaN"),
        ({"delta": -1.0}, r"delta must be a finite number in \(0, 10\]"),
    ]:
        args = {"prev": [[0.0, 0.0]], "nxt": [[1.0, 0.0]], "delta": 0.3, **kwargs}
        with pytest.raises(UsageError, match=match):
            straight_connection(**args)


@pytest.mark.parametrize(
    ("dist", "delta"),
    [(0.05, 0.05), (0.02, 0.05), (1.05, 0.03), (2.1, 0.06), (1.0, 0.07), (0.3, 0.1)],
)
def test_subdivide_uses_the_fewest_pieces_that_keep_every_gap_within_delta(dist, delta):
    # (1.05, 0.03) and (2.1, 0.06): ceil(dist / delta) rounds one piece short in floating point
    pts = subdivide(np.zeros(2), np.array([dist, 0.0]), delta)
    pieces = len(pts) + 1
    assert dist / pieces <= delta  # every gap within delta ...
    assert pieces == 1 or dist / (pieces - 1) > delta  # ... and one piece fewer would not do
    np.testing.assert_allclose(pts[:, 0], np.arange(1, pieces) * dist / pieces, rtol=1e-12)
    assert np.all(pts[:, 1] == 0.0)


@pytest.mark.parametrize("k", [3, 8, 15])
def test_running_out_of_steps_cuts_the_path_at_its_closest_approach(k):
    # the first k steps do not depend on max_steps, so the path cut at k is a prefix of the full
    # connection: kept up to its point closest to the target, or not at all when the start is
    # closer, then the straight tail (module docstring, guarantee 1)
    prev, nxt = PAIRS[7]
    full = connect_letters(prev, nxt)
    assert not full.fallback and full.steered > 15
    steps = full.points[:k]
    gaps = np.hypot(*(steps - nxt[0]).T)
    keep = int(np.argmin(gaps)) + 1
    if np.hypot(*(prev[-1] - nxt[0])) <= gaps[keep - 1]:
        keep = 0
    cut = connect_letters(prev, nxt, max_steps=k)
    assert (cut.steered, cut.target, cut.fallback) == (keep, 0, True)
    np.testing.assert_array_equal(cut.points[:keep], steps[:keep])
    tail_from = steps[keep - 1] if keep else prev[-1]
    np.testing.assert_allclose(cut.points[keep:], subdivide(tail_from, nxt[0], P.delta))


def test_every_result_field_of_a_joined_connection():
    for join in ("first", "retrace"):
        for prev, nxt in PAIRS[:10]:
            r = connect_letters(prev, nxt, join=join)
            assert r.fallback is False and isinstance(r.target, int)
            if join == "first":
                assert r.steered == len(r.points) and r.target == 0
            else:
                assert 0 <= r.target < len(nxt) and r.steered <= len(r.points)
            steps = np.hypot(*np.diff(connection_path(prev, r, nxt), axis=0).T)
            assert np.all(steps > 0)  # no point is repeated


@pytest.mark.parametrize("name", ["alpha_max", "theta_o", "theta_a", "theta_f", "theta_p"])
def test_each_bad_weight_is_named(name):
    with pytest.raises(UsageError, match=f"{name} must be"):
        connect_letters([[0.0, 0.0], [1.0, 0.0]], [[2.0, 0.0]], **{name: -1.0})


def test_a_letter_without_extent_starts_the_pen_towards_the_next_letter():
    prev = np.array([[1.0, 1.0], [1.0, 1.0]])  # a dot: no last segment to take a heading from
    result = connect_letters(prev, np.array([[3.0, 1.0], [3.5, 1.5]]))
    np.testing.assert_allclose(result.points[0], [1.0 + P.delta, 1.0], atol=1e-12)


def test_a_half_turn_per_step_is_allowed():
    prev, nxt = PAIRS[8]
    result = connect_letters(prev, nxt, alpha_max=math.pi)  # documented range (0, pi]
    check_guarantees(prev, nxt, result, P.delta, math.pi, P.max_steps)


def test_connect_sequence_offers_the_hand_method_and_keeps_spaces_straight():
    letters = [_arc((1.2 * k, 0.25), (0.25, 0.25), 180, 540) for k in range(3)]
    out = connect_sequence(letters, method="hand", breaks=[False, True])
    assert len(out) == 2
    straight = np.linspace(letters[1][-1], letters[2][0], len(out[1].points) + 2)[1:-1]
    np.testing.assert_allclose(out[1].points, straight, atol=1e-9)
    with pytest.raises(Exception, match="'hand', 'alg1' or 'straight'"):
        connect_sequence(letters, method="curly")


def test_connect_sequence_hand_joins_each_pair_as_hand_connection_or_lifts_the_pen():
    """Each pair of ``method="hand"`` is what :func:`hand_connection` makes of it (with the
    given settings), except where the writer lifts the pen (:func:`lifts_pen`) or a space
    separates the letters: there the straight pen-up travel."""
    from prg.pipeline.joins import hand_connection, lifts_pen

    stem_then_foot = np.array([[0.9, 1.0], [0.9, 0.5], [0.9, 0.0], [0.75, -0.12], [0.6, -0.1]])
    letters = [
        _arc((0.0, 0.25), (0.25, 0.25), 90, 400),  # leaves on its right: joined
        stem_then_foot,  # ends left of its stem: the pen lifts
        _arc((1.6, 0.25), (0.25, 0.25), 120, 420),
        _arc((2.4, 0.25), (0.25, 0.25), 90, 400),
        _arc((3.6, 0.25), (0.25, 0.25), 180, 540),
    ]
    params = ConnectionSettings(delta=0.03, alpha_max=math.radians(25.0), home_radius=0.3)
    breaks = [False, False, False, True]
    out = connect_sequence(letters, params, method="hand", breaks=breaks)
    lifted = [lifts_pen(a, b) for a, b in itertools.pairwise(letters)]
    assert lifted[1] and not lifted[0]  # the case holds both kinds of pair
    for i, (a, b) in enumerate(itertools.pairwise(letters)):
        if breaks[i] or lifted[i]:
            assert out[i].pen_up, i
            straight = straight_connection(a, b, params.delta)
            np.testing.assert_array_equal(out[i].points, straight.points)
        else:
            expected = hand_connection(a, b, letters, params)
            assert not out[i].pen_up, i
            _same_result(out[i], expected)
            assert out[i].steered > 0, i  # steered with the given settings, not straight
    with_defaults = connect_sequence(letters, method="hand", breaks=breaks)
    assert with_defaults[0].points.shape != out[0].points.shape or not np.allclose(
        with_defaults[0].points, out[0].points
    )  # the settings reach the joins


# ============================================================================= connection strokes


def letter_end(anchor, angle, length, n):
    """A straight stroke of ``n`` points ending at ``anchor`` heading ``angle`` (its tangent)."""
    t = np.linspace(0.0, -1.0, n)[::-1, None]  # ends at 0, also for n = 1
    return anchor + t * length * np.array([math.cos(angle), math.sin(angle)])


def letter_start(anchor, angle, length, n):
    """A slightly curved stroke of ``n`` points starting at ``anchor`` heading ``angle``."""
    t = np.linspace(0.0, 1.0, n)
    heading = angle + 1.5 * t
    return anchor + length * np.column_stack([t * np.cos(heading), t * np.sin(heading)])


@examples(100)
@given(
    delta=log_uniform(-3, 0),
    distance=st.one_of(st.just(0.0), log_uniform(-2, 3)),
    bearing=st.floats(-math.pi, math.pi),
    tangents=st.tuples(st.floats(-math.pi, math.pi), st.floats(-math.pi, math.pi)),
    lengths=st.tuples(log_uniform(-2, 2), log_uniform(-2, 2)),
    points=st.tuples(st.integers(1, 5), st.integers(1, 40)),
    origin=arrays(np.float64, 2, elements=st.floats(-100.0, 100.0)),
    join=st.sampled_from(["first", "retrace"]),
    method=st.sampled_from(["alg1", "straight"]),
)
def test_connections_between_any_endpoints_and_tangents_are_gap_free(
    delta, distance, bearing, tangents, lengths, points, origin, join, method
):
    """Letter A ends at ``origin`` heading ``tangents[0]``; letter B starts ``distance * delta``
    away (from touching to 1000 steps, far beyond ``max_steps``) heading ``tangents[1]``."""
    gap = distance * delta
    a_end = origin * delta
    b_start = a_end + gap * np.array([math.cos(bearing), math.sin(bearing)])
    prev = letter_end(a_end, tangents[0], lengths[0] * delta * 10, points[0])
    nxt = letter_start(b_start, tangents[1], lengths[1] * delta * 10, points[1])
    if method == "alg1":
        result = connect_letters(prev, nxt, delta=delta, join=join)
    else:
        result = straight_connection(prev, nxt, delta=delta)
    path = connection_path(prev, result, nxt)
    assert np.all(np.isfinite(result.points))
    # no gap, at the joins with both letters too (relative 1e-12: coordinate rounding)
    assert steps(path).max(initial=0.0) <= delta * (1 + 1e-12) + 1e-12 * np.abs(path).max()
    # bounded excursion: steered steps go at most steered * delta from A's end; the straight
    # tail and the straight joiner stay between their ends; "retrace" runs back along B
    reach = max(result.steered * delta, gap) + 1e-9 * (1 + np.abs(path).max())
    if result.target:
        reach = max(reach, np.hypot(*(nxt[: result.target + 1] - a_end).T).max() + delta)
    assert np.hypot(*(result.points - a_end).T).max(initial=0.0) <= reach
    if method == "straight" or result.steered == 0:  # a straight line from A's end to B's start
        cross = (result.points - a_end) @ np.array([-(b_start - a_end)[1], (b_start - a_end)[0]])
        assert np.abs(cross).max(initial=0.0) <= 1e-9 * (gap + delta) * (1 + np.abs(path).max())
