"""The handwriting data layer: alphabet, sources (UJI, synthetic), preprocessing, splits, loaders."""

from prg.alphabet import ALPHABET, NUM_CLASSES, char_to_label, label_to_char, text_to_labels
from prg.data.preprocess import (
    TRAJ_LAYOUT,
    normalise,
    preprocess_stroke,
    render,
    resample_arclength,
)

__all__ = [
    "ALPHABET",
    "NUM_CLASSES",
    "TRAJ_LAYOUT",
    "char_to_label",
    "label_to_char",
    "normalise",
    "preprocess_stroke",
    "render",
    "resample_arclength",
    "text_to_labels",
]
