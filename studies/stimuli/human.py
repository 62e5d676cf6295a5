"""The human samples of a study: every sample file under the given folders, sorted by word and
writer, with notes on the ones left out."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from prg.errors import UsageError
from studies.stimuli.json_samples import read_json_sample
from studies.stimuli.sample import ROBOT, Sample
from studies.stimuli.svg import read_svg

HUMAN_SUFFIXES = (".json", ".svg")


@dataclass
class HumanSamples:
    """Human samples found for a study.

    Attributes
    ----------
    by_word : dict of str to dict of str to Sample
        ``by_word[word][writer_id]``.
    notes : list of str
        Files and samples left out, and why.
    """

    by_word: dict[str, dict[str, Sample]] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    def writers(self) -> dict[str, list[str]]:
        """Writer ids per word, sorted."""
        return {w: sorted(s) for w, s in self.by_word.items()}


def load_human_samples(
    dirs: Iterable[str | Path],
    words: Sequence[str],
    accept_lifted: bool = False,
    delayed_strokes: bool = True,
) -> HumanSamples:
    """Read every human sample file under ``dirs`` (recursively) for the study's ``words``.

    Samples of other words, samples with a pen lift (unless ``accept_lifted``) and a second
    sample of the same word by the same writer are left out and listed in ``notes``. Delayed
    strokes (dots and bars written after the word) are no pen lift: the sample keeps them, or,
    with ``delayed_strokes`` False (the paper's single stroke), drops them with a note.

    Raises
    ------
    UsageError
        A folder that does not exist, or a file that cannot be read as a sample.
    """
    out = HumanSamples({w: {} for w in words})
    for root in dirs:
        root = Path(root)
        if not root.is_dir():
            raise UsageError(f"--human {root}: no such folder of human samples")
        for path in sorted(p for p in root.rglob("*") if p.suffix.lower() in HUMAN_SUFFIXES):
            if path.name.startswith(".") or not path.is_file():
                continue
            reader = read_svg if path.suffix.lower() == ".svg" else read_json_sample
            for sample in reader(path, root):
                if sample.word not in out.by_word:
                    out.notes.append(f"{path}: {sample.word!r} is not a study word; left out")
                elif sample.writer_id == ROBOT:
                    out.notes.append(f"{path}: writer id 'robot' is reserved; left out")
                elif sample.lifted and not accept_lifted:
                    out.notes.append(
                        f"{path}: {sample.writer_id}/{sample.word} was written with a pen lift; "
                        "left out (human.accept_lifted: true keeps it)"
                    )
                elif sample.writer_id in out.by_word[sample.word]:
                    out.notes.append(
                        f"{path}: a second {sample.word!r} by {sample.writer_id}; left out"
                    )
                else:
                    if sample.delayed and not delayed_strokes:
                        out.notes.append(
                            f"{path}: {sample.writer_id}/{sample.word}: its "
                            f"{len(sample.delayed)} delayed stroke(s) (dots, bars) are not drawn "
                            "(delayed_strokes: false)"
                        )
                        sample = sample.without_delayed()
                    out.by_word[sample.word][sample.writer_id] = sample
    return out
