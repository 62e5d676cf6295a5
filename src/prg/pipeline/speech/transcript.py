"""What a recogniser heard (:class:`Transcript`) and the text to write from it.

A raw transcript -> :func:`transcript_to_word`: letters and digits only, words separated by one
space, case applied -> the text to write, whose characters are all in :mod:`prg.alphabet`.
Spoken words carry no case, so the case of the written word is a choice (``SpeechSettings.case``).
With a lexicon, a free transcript is snapped to the nearest entry (:func:`snap_to_lexicon`).
"""

from __future__ import annotations

import unicodedata
from collections.abc import Sequence
from dataclasses import dataclass, field

from prg.alphabet import is_supported
from prg.errors import UsageError
from prg.pipeline.speech.settings import CASES


@dataclass(frozen=True)
class Transcript:
    """What a recogniser heard.

    Attributes
    ----------
    text : str
        The recogniser's raw output (for rescoring: the chosen lexicon word).
    word : str
        The text to write: alphabet characters, words separated by one space.
    backend, model : str
        Which recogniser (model: folder or hub name).
    seconds : float
        Wall time of recognition (after loading and resampling the audio).
    audio_seconds : float
        Duration of the audio.
    candidates : tuple of (str, float)
        Rescoring only: up to 5 lexicon words with their exact scores, best first (whisper:
        log-probability minus ``prior_weight`` times the log-probability on silence).
        The first is the chosen lexicon word; the whisper backend prunes words that
        provably score lower than it, so those after it are the best of the words it scored.
    """

    text: str
    word: str
    backend: str
    model: str
    seconds: float
    audio_seconds: float
    candidates: tuple[tuple[str, float], ...] = field(default=())


def _ascii_fold(text: str) -> str:
    """Accents removed (NFKD, combining marks dropped): "café" -> "cafe"."""
    decomposed = unicodedata.normalize("NFKD", text)
    return "".join(c for c in decomposed if not unicodedata.combining(c))


def transcript_to_word(text: str, case: str = "lower") -> str:
    """The text to write from a transcript: alphabet characters, words separated by one space.

    Accents are removed ("café" -> "cafe"); inside a word every other character (punctuation,
    apostrophes, hyphens) is dropped, joining its parts ("don't" -> "dont", "T-shirt" ->
    "tshirt"); words are split at whitespace; then ``case`` is applied.

    Parameters
    ----------
    text : str
        A recogniser's transcript, e.g. ``" Hello, world!"``.
    case : {"lower", "upper", "title"}

    Returns
    -------
    str
        E.g. ``"hello world"``; every character is in the alphabet or a single space.

    Raises
    ------
    UsageError
        If no letter or digit is left, or ``case`` is unknown.
    """
    if case not in CASES:
        raise UsageError(f"case {case!r} is unknown: accepted are {', '.join(CASES)}")
    words = ["".join(c for c in w if is_supported(c)) for w in _ascii_fold(text).split()]
    words = [w for w in words if w]
    if not words:
        raise UsageError(
            f"transcript {text!r} has no letters or digits to write: accepted are 0-9, A-Z, a-z"
        )
    if case == "lower":
        words = [w.lower() for w in words]
    elif case == "upper":
        words = [w.upper() for w in words]
    else:
        words = [w[:1].upper() + w[1:].lower() for w in words]
    return " ".join(words)


def edit_distance(a: str, b: str) -> int:
    """Levenshtein distance (insertions, deletions, substitutions, each cost 1)."""
    if len(a) < len(b):
        a, b = b, a
    previous = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        current = [i]
        for j, cb in enumerate(b, 1):
            current.append(min(previous[j] + 1, current[j - 1] + 1, previous[j - 1] + (ca != cb)))
        previous = current
    return previous[-1]


def lexicon_key(word: str) -> str:
    """Comparison key: lower-case letters and digits only (spaces and punctuation removed)."""
    return "".join(c for c in _ascii_fold(word).lower() if is_supported(c))


def snap_to_lexicon(word: str, lexicon: Sequence[str]) -> str:
    """The lexicon entry nearest to ``word`` by edit distance.

    Comparison ignores case, spaces and punctuation; ties go to the entry whose length is
    closest to the word's, then to the earlier entry.

    Parameters
    ----------
    word : str
        A transcript or word.
    lexicon : sequence of str
        Candidate entries (non-empty).

    Returns
    -------
    str
        The chosen entry, as written in ``lexicon``.
    """
    if not lexicon:
        raise UsageError("lexicon is empty: give at least one word")
    key = lexicon_key(word)

    def cost(item: tuple[int, str]) -> tuple[int, int, int]:
        index, entry = item
        other = lexicon_key(entry)
        return edit_distance(key, other), abs(len(other) - len(key)), index

    return min(enumerate(lexicon), key=cost)[1]


def letter_error_rate(hypothesis: str, reference: str) -> float:
    """Edit distance between the two keys (case, spaces and punctuation ignored) / reference length."""
    ref = lexicon_key(reference)
    return edit_distance(lexicon_key(hypothesis), ref) / max(len(ref), 1)
