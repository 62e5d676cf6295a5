"""What every recogniser back-end is (:class:`Recogniser`), and where a back-end's model is
loaded from."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

from prg.errors import UsageError
from prg.pipeline.speech.dependencies import first_line

if TYPE_CHECKING:
    import numpy as np

    from prg.pipeline.speech.settings import SpeechSettings


class Recogniser(Protocol):
    """A speech recogniser backend."""

    backend: str
    model: str

    def transcribe(self, audio: np.ndarray, params: SpeechSettings) -> str:
        """Raw transcript of 16 kHz mono float32 ``audio``."""

    def score(self, audio: np.ndarray, words: Sequence[str], params: SpeechSettings) -> np.ndarray:
        """Log-probability of each of ``words`` being what ``audio`` says (NaN: not scored,
        shown to be below the best; -inf: the model cannot produce the word)."""


def model_source(model: str, backend: str) -> str:
    """What to load ``model`` from: the folder it names (``~`` expanded), else the name as given
    (a hub name, looked up in the local cache by the back-end).

    ``./x``, ``/x``, ``~/x``, ``a/b/c`` and ``a\\b`` are paths, and one that is no folder is an
    error; ``name`` and ``org/name`` may be hub names.
    """
    path = Path(model).expanduser()
    looks_like_path = model.startswith((".", "/", "~")) or model.count("/") > 1 or "\\" in model
    if looks_like_path and not path.is_dir():
        raise UsageError(
            f"speech model folder {model!r} ({backend}) does not exist: give a model folder "
            "or a hub name already in the local cache"
        )
    return str(path) if path.is_dir() else model


def not_cached(backend: str, model: str, folders: str, err: BaseException) -> UsageError:
    """The error for a ``model`` that is neither one of the back-end's ``folders`` (e.g. "a
    local model folder") nor in the local Hugging Face cache; ``err`` is the loader's."""
    return UsageError(
        f"{backend} model {model!r} is neither {folders} nor in the local "
        f"Hugging Face cache (nothing is downloaded); {first_line(err)}"
    )
