"""Tests of ``studies.design`` (moved from the suite on: study designs: the YAML files, Latin-
square positions, foils, lists A/B, attention checks)."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from prg.errors import UsageError
from studies.design import (
    ROBOT,
    Trial,
    assign_row,
    balance_notes,
    fnv1a32,
    latin_square,
    load_study,
    readability_rows,
    robot_positions,
    split_lists,
    study_from_dict,
    turing_rows,
    with_checks,
    word_orders,
)
from tests.helpers.study_design import REPO, WORDS, readability, turing


def writers_for(words, n=10):
    return {w: [f"w{k:02d}" for k in range(n)] for w in words}


# ---------------------------------------------------------------------------- Latin square
@settings(max_examples=40, deadline=None)
@given(n=st.integers(1, 9), seed=st.integers(0, 2**32 - 1))
def test_latin_square_has_every_symbol_once_per_row_and_column(n, seed):
    square = latin_square(n, np.random.default_rng(seed))
    expected = list(range(n))
    assert all(sorted(row) == expected for row in square)
    assert all(sorted(col) == expected for col in square.T)


@settings(max_examples=40, deadline=None)
@given(
    k=st.integers(2, 6),
    words_per=st.integers(1, 4),
    people_per=st.integers(1, 6),
    seed=st.integers(0, 10_000),
)
def test_each_robot_position_equally_often_per_participant_and_per_word(
    k, words_per, people_per, seed
):
    n_words, n_people = k * words_per, k * people_per
    pos = robot_positions(n_people, n_words, k, seed)
    assert pos.min() >= 0 and pos.max() < k
    for p in range(n_people):  # within each participant
        assert np.bincount(pos[p], minlength=k).tolist() == [words_per] * k
    for w in range(n_words):  # for every word, across participants
        assert np.bincount(pos[:, w], minlength=k).tolist() == [people_per] * k
    assert np.bincount(pos.ravel(), minlength=k).tolist() == [n_words * people_per] * k


@settings(max_examples=30, deadline=None)
@given(
    k=st.integers(2, 6),
    n_words=st.integers(1, 15),
    n_people=st.integers(1, 20),
    seed=st.integers(0, 99),
)
def test_robot_positions_are_within_one_of_even_when_counts_do_not_divide(
    k, n_words, n_people, seed
):
    pos = robot_positions(n_people, n_words, k, seed)
    for p in range(n_people):
        counts = np.bincount(pos[p], minlength=k)
        assert counts.max() - counts.min() <= 1
    for w in range(n_words):
        counts = np.bincount(pos[:, w], minlength=k)
        assert counts.max() - counts.min() <= 1


def test_word_orders_are_seeded_permutations_that_differ_between_participants():
    orders = word_orders(50, 10, seed=3)
    assert all(sorted(o) == list(range(10)) for o in orders)
    assert len({tuple(o) for o in orders}) > 40
    np.testing.assert_array_equal(orders, word_orders(50, 10, seed=3))
    assert not np.array_equal(orders, word_orders(50, 10, seed=4))


# ---------------------------------------------------------------------------- study 1
def test_turing_rows_show_each_word_once_with_the_robot_at_its_latin_square_position():
    config = turing()
    rows = turing_rows(config, writers_for(WORDS))
    positions = robot_positions(50, 10, 5, config.seed)
    assert len(rows) == 50
    for row in rows:
        assert row.list_id == f"row-{row.row + 1:03d}"
        assert sorted(t.word for t in row.trials) == sorted(WORDS)
        for trial in row.trials:
            assert len(trial.options) == 5
            assert trial.options[trial.robot_index] == ROBOT
            assert trial.options.count(ROBOT) == 1
            assert len(set(trial.options)) == 5  # four different human writers
            assert trial.robot_index == positions[row.row, WORDS.index(trial.word)]


def test_turing_foils_are_sampled_per_trial_from_all_writers():
    rows = turing_rows(turing(), writers_for(WORDS))
    used = Counter(w for row in rows for t in row.trials for w in t.options if w != ROBOT)
    assert set(used) == {f"w{k:02d}" for k in range(10)}
    foil_sets = {frozenset(t.options) for row in rows for t in row.trials if t.word == "cat"}
    assert len(foil_sets) > 20


def test_turing_uses_the_first_human_writers_and_needs_enough():
    config = turing(human_writers=4)
    rows = turing_rows(config, writers_for(WORDS, n=6))
    assert {w for row in rows for t in row.trials for w in t.options} == {
        ROBOT,
        "w00",
        "w01",
        "w02",
        "w03",
    }
    with pytest.raises(UsageError, match="'bell' has 3 human writers, the design needs 4"):
        turing_rows(config, writers_for(WORDS, n=3))


def test_turing_design_is_reproducible_from_its_seed():
    a = turing_rows(turing(), writers_for(WORDS))
    assert a == turing_rows(turing(), writers_for(WORDS))
    assert a != turing_rows(turing(seed=8), writers_for(WORDS))


def test_attention_check_repeats_the_screen_before_it_and_is_flagged():
    checks = [{"after_trial": 5, "instruction": "choose 2", "expect": {"choose_sample": 2}}]
    rows = turing_rows(turing(attention_checks=checks), writers_for(WORDS))
    for row in rows:
        assert len(row.trials) == 11
        check = row.trials[5]
        assert check.is_attention_check and check.expect == {"chosen_index": 1}
        assert check.instruction == "choose 2"
        assert check.options == row.trials[4].options  # nothing new is shown
        assert sum(t.is_attention_check for t in row.trials) == 1


def test_attention_check_of_a_named_word_and_at_the_start():
    checks = [
        {"after_trial": 0, "instruction": "a", "expect": {"choose_sample": 1}, "word": "moon"},
        {"after_trial": 10, "instruction": "b", "expect": {"choose_sample": 5, "confidence": 1}},
    ]
    row = turing_rows(turing(attention_checks=checks), writers_for(WORDS))[0]
    assert row.trials[0].is_attention_check and row.trials[0].word == "moon"
    assert row.trials[0].options == next(t.options for t in row.trials[1:] if t.word == "moon")
    assert row.trials[-1].is_attention_check
    assert row.trials[-1].expect == {"chosen_index": 4, "confidence": 1}
    assert row.trials[-1].options == row.trials[-2].options


def test_with_checks_inserts_after_the_given_number_of_trials():
    main = [Trial(w, (ROBOT,)) for w in "abc"]
    check = Trial("x", (ROBOT,), is_attention_check=True)
    out = with_checks(main, [(2, check), (0, check), (3, check)])
    assert [t.word for t in out] == ["x", "a", "b", "x", "c", "x"]


# ---------------------------------------------------------------------------- study 2
def test_lists_a_and_b_swap_human_and_robot_halves():
    lists = split_lists(WORDS, ("A", "B"), seed=1)
    a, b = lists["A"], lists["B"]
    assert Counter(a.values()) == {"human": 5, ROBOT: 5}
    assert all({a[w], b[w]} == {"human", ROBOT} for w in WORDS)


@settings(max_examples=25, deadline=None)
@given(
    half=st.integers(1, 6),
    pairs=st.integers(1, 12),
    n_writers=st.integers(1, 6),
    seed=st.integers(0, 1000),
)
def test_readability_shows_each_word_by_each_source_equally_often(half, pairs, n_writers, seed):
    words = [f"w{'a' * (i + 1)}" for i in range(2 * half)]
    config = study_from_dict(
        {
            "name": "r",
            "kind": "readability",
            "words": words,
            "participants": 2 * pairs,
            "seed": seed,
            "human_writers": n_writers,
        }
    )
    rows = readability_rows(config, writers_for(words, n_writers))
    seen = Counter((t.word, t.writer) for row in rows for t in row.trials)
    assert set(seen.values()) == {pairs}  # every word x writer, equally often
    assert len(seen) == 2 * len(words)
    for row in rows:
        assert row.list_id == ("A" if row.row % 2 == 0 else "B")
        assert sorted(t.word for t in row.trials) == sorted(words)
        assert Counter(t.writer for t in row.trials) == {"human": half, ROBOT: half}


def test_readability_rotates_the_human_writer_of_each_word():
    rows = readability_rows(readability(participants=40, human_writers=4), writers_for(WORDS))
    for word in WORDS:
        humans = Counter(
            t.options[0] for r in rows for t in r.trials if t.word == word and t.writer == "human"
        )
        assert humans == {"w00": 5, "w01": 5, "w02": 5, "w03": 5}


def test_readability_attention_check_repeats_the_participants_own_sample():
    checks = [{"after_trial": 3, "instruction": "type blue", "expect": {"typed_text": "blue"}}]
    for row in readability_rows(readability(attention_checks=checks), writers_for(WORDS)):
        check = row.trials[3]
        assert check.is_attention_check and check.expect == {"typed_text": "blue"}
        assert check.options == row.trials[2].options and check.word == row.trials[2].word


def test_counts_that_break_exact_balance_are_reported():
    assert balance_notes(turing()) == [] and balance_notes(readability()) == []
    notes = balance_notes(turing(participants=12, words=WORDS[:7]))
    assert [n.split(":")[0] for n in notes] == [
        "7 words are not a multiple of 5 options",
        "12 participants are not a multiple of 5 options",
    ]
    assert balance_notes(readability(participants=31)) == [
        "31 participants is odd: list A is used once more than list B"
    ]


# ---------------------------------------------------------------------------- assignment
def test_fnv1a32_matches_the_reference_vectors():
    assert fnv1a32("") == 0x811C9DC5
    assert fnv1a32("a") == 0xE40C292C
    assert fnv1a32("foobar") == 0xBF9CF968


def test_assign_row_is_stable_and_fills_rows_about_evenly():
    assert assign_row("5f3a9c", 50, "turing") == assign_row("5f3a9c", 50, "turing")
    counts = Counter(assign_row(f"pid{i:05d}", 10, "turing") for i in range(5000))
    assert set(counts) == set(range(10))
    assert max(counts.values()) < 600 and min(counts.values()) > 400


def test_the_trial_limit_is_named_and_the_largest_study_is_accepted():
    """participants x trials each above MAX_TRIALS is refused with the limit (designing
    200,000 trials takes about 4 s on one core, 1,000,000 about 18 s)."""
    from studies.design import MAX_TRIALS

    words = f"words=[{', '.join(f'w{chr(97 + i // 26)}{chr(97 + i % 26)}' for i in range(20))}]"
    most = MAX_TRIALS // (20 + 1)  # 20 words + the attention check
    with pytest.raises(UsageError, match=f"is {(most + 1) * 21} trials; at most {MAX_TRIALS}"):
        load_study(REPO / "conf/study/turing.yaml", [f"participants={most + 1}", words])
    assert load_study(REPO / "conf/study/turing.yaml", [f"participants={most}", words])
