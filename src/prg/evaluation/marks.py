"""A geometric check of the delayed strokes (i/j dots, t/f bars) of written words.

The coherence classifiers were trained on single strokes and cannot see a dot, so the marks are
judged on geometry, from the :class:`~prg.pipeline.word.WordTrajectory` alone (not from how
:mod:`prg.pipeline.marks` placed them):

* every dotted letter (``MarkSettings.dotted``) has a **dot**: a mark smaller than a tenth of the
  letter's size (its larger extent), entirely above the letter's top but by less than twice its
  size,
  its centre within the letter's column (the x-range of the letter's points);
* every crossed letter (``MarkSettings.crossed``) has a **bar**: a mark wider than tall whose path
  crosses the letter's path, at a height between 15 % and 90 % of the letter's;
* no mark is left over, and each mark serves one letter.

:func:`check_marks` lists the problems of one word; :func:`check_writer` runs it on every one of
the 62 classes written alone and on random words, and :func:`marks_figure` draws the classes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from prg.alphabet import ALPHABET
from prg.pipeline.marks import MarkSettings
from prg.pipeline.word import WordTrajectory


def _crosses(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Points where polyline ``a`` (n, 2) crosses polyline ``b`` (m, 2) (proper crossings of
    their segments), shape (k, 2)."""
    p, r = a[:-1, None, :], (a[1:] - a[:-1])[:, None, :]
    q, s = b[None, :-1, :], (b[1:] - b[:-1])[None, :, :]
    denom = r[..., 0] * s[..., 1] - r[..., 1] * s[..., 0]
    qp = q - p
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (qp[..., 0] * s[..., 1] - qp[..., 1] * s[..., 0]) / denom
        u = (qp[..., 0] * r[..., 1] - qp[..., 1] * r[..., 0]) / denom
    hit = (denom != 0) & (t >= 0) & (t <= 1) & (u >= 0) & (u <= 1)
    i, j = np.nonzero(hit)
    return a[:-1][i] + t[i, j][:, None] * (a[1:] - a[:-1])[i]


def _is_dot(mark: np.ndarray, letter: np.ndarray) -> bool:
    lo, hi = letter.min(axis=0), letter.max(axis=0)
    size = (hi - lo).max()  # the letter's larger extent: a flattened letter keeps a scale
    centre_x = (mark[:, 0].min() + mark[:, 0].max()) / 2
    return bool(
        np.ptp(mark, axis=0).max() < 0.1 * size
        and mark[:, 1].min() > hi[1]
        and mark[:, 1].max() < hi[1] + 2 * size
        and lo[0] - 1e-6 <= centre_x <= hi[0] + 1e-6  # cm: rounding on a straight stem
    )


def _is_bar(mark: np.ndarray, letter: np.ndarray) -> bool:
    width, tall = np.ptp(mark, axis=0)
    if not width > tall:
        return False
    low, height = letter[:, 1].min(), np.ptp(letter[:, 1])
    rel = (_crosses(mark, letter)[:, 1] - low) / height
    return bool(np.any((rel >= 0.15) & (rel <= 0.9)))


def check_marks(word: WordTrajectory, settings: MarkSettings | None = None) -> list[str]:
    """The problems of a word's delayed strokes (empty: every mark where it belongs).

    Parameters
    ----------
    word : WordTrajectory
    settings : MarkSettings, optional
        Which letters need a dot or a bar.

    Returns
    -------
    list of str
        One line per problem, naming the letter (``'t' (letter 3)``).
    """
    settings = settings or MarkSettings()
    marks = [word.segment_points(k) for k, kind in enumerate(word.segment_kinds) if kind == "mark"]
    used: set[int] = set()
    problems = []
    for i, (char, letter) in enumerate(word.letters):
        kind = settings.mark_of(char)
        if kind is None:
            continue
        test = _is_dot if kind == "dot" else _is_bar
        centre = letter[:, 0].mean()
        fits = [k for k, m in enumerate(marks) if k not in used and test(m, letter)]
        if not fits:
            where = "above its stem" if kind == "dot" else "across its stem"
            problems.append(f"{char!r} (letter {i + 1}) has no {kind} {where}")
            continue
        used.add(min(fits, key=lambda k: abs(marks[k][:, 0].mean() - centre)))
    left = len(marks) - len(used)
    if left:
        problems.append(f"{left} mark(s) belong to no letter that needs one")
    return problems


@dataclass
class MarksCheck:
    """:func:`check_writer`'s result: words checked, the failures, and the words written."""

    classes: dict[str, list[str]] = field(default_factory=dict)  # class -> problems
    words: dict[str, list[str]] = field(default_factory=dict)  # random word -> problems
    marks: int = 0  # marks checked in all
    written: dict[str, WordTrajectory] = field(default_factory=dict)

    @property
    def failures(self) -> dict[str, list[str]]:
        return {w: p for w, p in {**self.classes, **self.words}.items() if p}

    def summary(self) -> dict:
        return {
            "classes": len(self.classes),
            "classes_passed": sum(not p for p in self.classes.values()),
            "words": len(self.words),
            "words_passed": sum(not p for p in self.words.values()),
            "marks_checked": self.marks,
            "failures": self.failures,
        }


def random_words(n: int, seed: int = 0, lengths: tuple[int, int] = (3, 10)) -> list[str]:
    """``n`` random strings over the 62 classes, ``lengths`` letters (inclusive), seeded."""
    rng = np.random.default_rng(seed)
    return [
        "".join(rng.choice(list(ALPHABET), size=int(rng.integers(lengths[0], lengths[1] + 1))))
        for _ in range(n)
    ]


def check_writer(
    write,
    n_words: int = 200,
    seed: int = 0,
    settings: MarkSettings | None = None,
    progress: bool = True,
) -> MarksCheck:
    """Write each of the 62 classes alone and ``n_words`` random words with ``write(text) ->
    WordTrajectory`` and check their marks."""
    from tqdm.auto import tqdm

    result = MarksCheck()
    classes, words = list(ALPHABET), random_words(n_words, seed)
    texts = tqdm([*classes, *words], desc="checking marks", unit="word", disable=not progress)
    for i, text in enumerate(texts):
        word = write(text)
        result.marks += word.segment_kinds.count("mark")
        (result.classes if i < len(classes) else result.words)[text] = check_marks(word, settings)
        result.written[text] = word
    return result


def marks_figure(check: MarksCheck, path: Path, extra_words: int = 6) -> Path:
    """The 62 classes as written (marks in their own colour), then a few random words."""
    from prg.files import atomic_path
    from prg.plotting import pyplot

    plt = pyplot()
    letters = [check.written[c] for c in ALPHABET if c in check.written]
    words = [w for t, w in check.written.items() if t not in ALPHABET][:extra_words]
    cols, pairs = 16, -(-len(words) // 2)
    rows = -(-len(letters) // cols)
    fig = plt.figure(figsize=(cols * 0.9, rows * 1.3 + pairs * 1.8), dpi=120)
    grid = fig.add_gridspec(rows + pairs, cols, height_ratios=[1.3] * rows + [1.8] * pairs)
    for i, word in enumerate(letters):
        _draw(fig.add_subplot(grid[i // cols, i % cols]), word)
    half = cols // 2
    for j, word in enumerate(words):  # two words a row
        _draw(fig.add_subplot(grid[rows + j // 2, (j % 2) * half : (j % 2 + 1) * half]), word)
    fig.suptitle("delayed strokes (purple) after the cursive body: every class, then random words")
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png", metadata={"Software": None})
    finally:
        plt.close(fig)
    return path


def _draw(ax, word: WordTrajectory) -> None:
    from prg.plotting import CONNECTION, FIGURE_INK, MARK, hex_colour

    colours = {"letter": FIGURE_INK, "connection": CONNECTION, "mark": MARK}
    for kind, pts in word.polylines(highlight=False):
        ax.plot(*pts.T, color=hex_colour(colours[kind]), lw=1.6, solid_capstyle="round")
    ax.set_aspect("equal")
    ax.set_ylim(-0.9, 2.0)
    ax.axis("off")


__all__ = ["MarksCheck", "check_marks", "check_writer", "marks_figure", "random_words"]
