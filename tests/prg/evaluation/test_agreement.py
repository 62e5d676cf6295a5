"""Agreement of two classifiers' readings, against a hand count."""

import pytest
import torch

from prg.alphabet import ALPHABET
from prg.evaluation.agreement import agreement


def test_agreement_of_two_readings_matches_a_hand_count():
    # true class, first reading, second reading; o/O are shape twins, a/b are not
    cases = [
        ("a", "a", "a"),  # both right, same class
        ("a", "a", "b"),  # first right, second wrong
        ("o", "o", "O"),  # both right folded; different classes, same twin group
        ("b", "a", "a"),  # both wrong, same class
        ("b", "b", "a"),  # first right, second wrong
    ]
    labels, first, second = (torch.tensor([ALPHABET.index(c[i]) for c in cases]) for i in range(3))
    out = agreement(first, second, labels)
    assert out["coherence_second"] == pytest.approx(1 / 5)  # only the first case exactly
    assert out["coherence_folded_second"] == pytest.approx(2 / 5)  # and the O for o
    assert out["agreement"] == pytest.approx(2 / 5)  # cases 1 and 4
    assert out["agreement_folded"] == pytest.approx(3 / 5)  # and case 3
    assert out["difference"] == pytest.approx(4 / 5 - 1 / 5)
    assert out["difference_folded"] == pytest.approx(4 / 5 - 2 / 5)
    assert out["coherence_folded_both"] == pytest.approx(2 / 5)  # cases 1 and 3
