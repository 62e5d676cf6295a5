"""Tests of ``prg.pipeline.decode`` (moved from the suite on: generate: per-letter decoding, input
subsets per family, rest-to-rest timing, one DMP a word)."""

import logging

import numpy as np
import pytest
import torch

from prg.errors import UsageError
from prg.models.avae import AVAE
from prg.models.cvae import CVAE
from prg.models.muse import MUSE
from prg.pipeline.decode import decode_letters, infer_text, usable_inputs


def _inputs(n: int) -> dict[str, torch.Tensor]:
    g = torch.Generator().manual_seed(0)
    return {
        "label": torch.randint(0, 62, (n,), generator=g),
        "traj": torch.randn(n, 200, generator=g) * 0.3,
        "image": torch.rand(n, 1, 28, 28, generator=g),
    }


def test_muse_uses_every_given_modality_and_avae_drops_what_it_cannot_use(caplog):
    torch.manual_seed(0)
    data = _inputs(3)
    assert set(usable_inputs(MUSE().eval(), data)) == {"label", "traj", "image"}
    with caplog.at_level(logging.WARNING):
        chosen = usable_inputs(AVAE(("traj", "label")).eval(), {"label": data["label"]})
    assert set(chosen) == {"label"} and not caplog.records
    with caplog.at_level(logging.WARNING):
        chosen = usable_inputs(AVAE(("traj", "image")).eval(), data)
    assert len(chosen) == 1 and "ignoring" in caplog.text


def test_a_family_given_nothing_it_accepts_is_refused_by_name():
    with pytest.raises(UsageError, match="cvae cannot use the given inputs \\{image\\}"):
        usable_inputs(CVAE(), {"image": torch.rand(2, 1, 28, 28)})


def test_decoding_gives_one_trajectory_per_letter_and_is_seeded():
    torch.manual_seed(0)
    model = MUSE().eval()
    data = {"label": _inputs(4)["label"]}
    mean = decode_letters(model, data)
    assert mean.shape == (4, 100, 2) and np.isfinite(mean).all()
    a = decode_letters(model, data, temperature=1.0, seed=1)
    b = decode_letters(model, data, temperature=1.0, seed=1)
    c = decode_letters(model, data, temperature=1.0, seed=2)
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)


def test_text_is_read_from_images_by_a_family_that_generates_labels():
    torch.manual_seed(0)
    images = {"image": torch.rand(3, 1, 28, 28)}
    text = infer_text(MUSE().eval(), images)
    assert len(text) == 3 and text.isalnum()
    with pytest.raises(UsageError, match="avae_ti cannot read letters"):
        infer_text(AVAE(("traj", "image")).eval(), images)


def _probabilities(first: str, second: str) -> "torch.Tensor":
    """Per-letter class probabilities whose most probable letters spell ``first`` and whose next
    most probable spell ``second`` (0.5 and 0.3, the rest spread over the other classes)."""
    import torch

    from prg.alphabet import NUM_CLASSES, char_to_label

    probs = torch.full((len(first), NUM_CLASSES), 0.2 / (NUM_CLASSES - 2))
    for i, (a, b) in enumerate(zip(first, second, strict=True)):
        probs[i, char_to_label(a)] = 0.5
        probs[i, char_to_label(b)] = 0.3
    return probs


@pytest.mark.parametrize(
    "first, second, meant",
    [
        ("DeII", "bell", "bell"),  # most letters small: b and l are the best small readings
        ("ca5", "cat", "cat"),  # a digit in a word of letters
        ("jumP", "jump", "jump"),  # P/p: the same shape once size is normalised away
        ("sPOT", "SPOT", "SPOT"),
        ("Cat", "cat", "cat"),
        ("oXVw", "OxvW", "oXVw"),  # only twins, no evidence either way: as read
        ("beII", "bSrt", "bell"),  # I counts for l: the same vertical stroke
        ("Ab", "ab", "ab"),  # A and b are each read best as small letters
        ("2O24", "2024", "2024"),  # a number: O re-read as a digit
        ("Hm", "hM", "Hm"),  # capitals and small letters equally probable: as read
    ],
)
def test_letters_are_read_in_the_kind_of_their_word(first, second, meant):
    from prg.pipeline.decode import read_in_context

    assert read_in_context(_probabilities(first, second)) == meant
