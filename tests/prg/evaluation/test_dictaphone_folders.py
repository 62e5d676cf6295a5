"""prg.evaluation.dictaphone.word_folders: no two words of any list share a folder."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from prg.evaluation.dictaphone import RESERVED_FOLDERS, word_folders


def test_plain_words_keep_their_names():
    assert word_folders(["bell", "cat", "jump"]) == {"bell": "bell", "cat": "cat", "jump": "jump"}


def test_duplicates_reserved_names_and_case_twins():
    folders = word_folders(["cat", "inputs", "cat", "CAT", "Inputs", "cat2"])
    assert folders == {
        "cat": "cat",
        "inputs": "inputs-2",
        "CAT": "CAT-2",
        "Inputs": "Inputs-3",
        "cat2": "cat2",
    }


@given(
    st.lists(
        st.sampled_from(["a", "A", "inputs", "INPUTS", "b", "a2"]) | st.text("aA1", min_size=1)
    )
)
def test_no_two_words_share_a_folder_up_to_case(words):
    folders = word_folders(words)
    assert list(folders) == list(dict.fromkeys(words))
    names = [name.casefold() for name in folders.values()]
    assert len(set(names)) == len(names)
    assert not {n.casefold() for n in RESERVED_FOLDERS} & set(names)
