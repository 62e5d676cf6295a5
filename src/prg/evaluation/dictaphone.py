"""The paper's Table II (the Robotic Dictaphone): words written from sound and from letter images.

For each word the writer writes it twice: **from sound** (x_S: the word spoken by espeak-ng into a
WAV file, recognised by the writer's speech settings; the transcript's letters are the model's
only input) and **from images** (x_I: one image per letter, the first original test-split image
of its class; the images are the model's only input, the word's known spelling sizes and places
the letters, and what the model itself reads from the images is reported beside it).
:func:`dictaphone_table` writes every case's inputs and outputs into a folder and returns the
table's rows; :func:`table2_figure` and :func:`table2_markdown` draw and print them.
"""

from __future__ import annotations

import logging
import shutil
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
from scipy.signal import spectrogram

from prg.alphabet import char_to_label
from prg.errors import UsageError
from prg.files import atomic_path
from prg.pipeline.speech import SAMPLE_RATE
from prg.pipeline.timing import timed_body
from prg.pipeline.word import WordTrajectory
from prg.plotting import MARK, hex_colour, pyplot
from prg.writer import Writer, WriteResult

log = logging.getLogger(__name__)

CHANNELS = ("sound", "image")


def espeak(text: str, path: Path, voice: str = "en-us", speed: int = 150) -> Path:
    """Speak ``text`` with espeak-ng into the WAV file ``path``."""
    if shutil.which("espeak-ng") is None:
        raise UsageError("espeak-ng is not installed: apt-get install espeak-ng (make setup)")
    result = subprocess.run(
        ["espeak-ng", "-v", voice, "-s", str(int(speed)), "-w", str(path), text],
        capture_output=True,
        text=True,
    )
    if result.returncode != 0 or not path.exists():
        message = " ".join(result.stderr.split()) or f"exit code {result.returncode}"
        raise UsageError(f"espeak-ng could not speak {text!r} with voice {voice!r}: {message}")
    return path


def letter_images(test: dict[str, np.ndarray], word: str) -> list[np.ndarray]:
    """One dark-on-light image per letter of ``word``: the first original (non-augmented) test
    sample of its class, else the first augmented one."""
    images = []
    for char in word:
        label = char_to_label(char)
        matches = np.flatnonzero(test["label"] == label)
        if matches.size == 0:
            raise UsageError(f"the test split has no image of {char!r}: cannot show {word!r}")
        originals = matches[~test["augmented"][matches]]
        index = originals[0] if originals.size else matches[0]
        images.append(255 - test["image"][index])
    return images


def dmp_rmse_mm(result: WriteResult) -> float:
    """RMSE (mm) of the DMP rollout against the timed demonstration it was fitted to."""
    samples, _ = timed_body(result.word.body, result.settings)
    return float(np.sqrt(np.mean(np.sum((result.rollout - samples) ** 2, axis=1))) * 10)


RESERVED_FOLDERS = ("inputs",)
"""Folder names of :func:`dictaphone_table`'s own outputs, which no word's folder may take."""


def word_folders(words: list[str]) -> dict[str, str]:
    """The folder of each distinct word of ``words``: the word itself, unless that name is
    taken, by one of :data:`RESERVED_FOLDERS` or by an earlier word up to case (``Cat`` after
    ``cat``: one folder on a file system that ignores case), then the word with ``-2``, ``-3``
    ... appended (a word holds only letters and digits, so such a name is never another word's).
    No two words ever share a folder, whatever the list."""
    taken = {name.casefold() for name in RESERVED_FOLDERS}
    folders: dict[str, str] = {}
    for word in words:
        if word in folders:
            continue
        name, n = word, 1
        while name.casefold() in taken:
            n += 1
            name = f"{word}-{n}"
        taken.add(name.casefold())
        folders[word] = name
    return folders


def dictaphone_table(
    writer: Writer,
    words: list[str],
    channels: list[str],
    folder: Path,
    test: dict[str, np.ndarray] | None = None,
    voice: str = "en-us",
    speed: float = 150,
    record: bool = True,
) -> tuple[list[dict[str, Any]], dict]:
    """Write every word from each channel into ``folder``: ``inputs/<word>.wav``,
    ``inputs/<word>/<i>_<c>.png`` and ``<word>/<channel>/`` (as :meth:`WriteResult.save`).

    A word given twice is written once (the first time). ``<word>`` is the word's folder name,
    :func:`word_folders`: the word itself unless it names one of the table's own folders
    (``inputs``) or an earlier word up to case, then ``<word>-2`` ...; each row names it
    (``folder``).

    Returns the table's rows (what was perceived and written, latency, DMP error, size) and the
    figure's items (inputs and written words, for :func:`table2_figure`).
    """
    rows, items = [], {}
    inputs_dir = folder / "inputs"
    inputs_dir.mkdir(parents=True, exist_ok=True)
    folders = word_folders(words)
    for word, name in folders.items():
        if name != word:
            log.info("%s: written into the folder %s (%s is taken)", word, name, word)
        for channel in channels:
            if channel == "sound":
                wav = espeak(word, inputs_dir / f"{name}.wav", voice, speed)
                result = writer.write(audio=wav)
                perceived = result.text
                items[word, channel] = result.perception.audio
            else:
                pictures = letter_images(test, word)
                (inputs_dir / name).mkdir()
                for i, image in enumerate(pictures):
                    _save_png(image, inputs_dir / name / f"{i}_{word[i]}.png")
                perception = writer.perceive(images=inputs_dir / name, spelling=word, read=True)
                result = writer.generate(perception)
                perceived = perception.read or ""
                items[word, channel] = pictures
            result.save(folder / name / channel, record=record)
            seconds = result.timings["total"]
            rows.append(
                {
                    "word": word,
                    "folder": name,
                    "channel": channel,
                    "perceived": perceived,
                    "correct": perceived == word,
                    "correct_folded": same_shapes(perceived, word),
                    "written": result.text,
                    "seconds": round(seconds, 3),
                    "dmp_rmse_mm": round(dmp_rmse_mm(result), 4),
                    "path_length_cm": round(result.word.path_length, 2),
                    "duration_s": round(result.word.duration_s, 2),
                }
            )
            log.info(
                "%s from %s: perceived %r, wrote %r in %.2f s",
                word,
                channel,
                perceived,
                result.text,
                seconds,
            )
            items[word, channel, "word"] = result.word
    return rows, items


def same_shapes(perceived: str, word: str) -> bool:
    """Whether ``perceived`` is ``word`` up to shape twins, letter by letter (``beii`` for
    ``bell``: a single-stroke l and a dotless i are the same vertical bar;
    :data:`~prg.evaluation.classifiers.SHAPE_TWINS`, the convention of the folded coherence)."""
    from prg.evaluation.classifiers import FOLD

    if len(perceived) != len(word):
        return False
    try:
        pairs = [(char_to_label(a), char_to_label(b)) for a, b in zip(perceived, word)]
    except UsageError:  # a character the alphabet lacks is no letter of the word
        return False
    return all(FOLD[a] == FOLD[b] for a, b in pairs)


def accuracy(rows: list[dict], channel: str, folded: bool = False) -> float | None:
    """The share of ``channel``'s rows whose word was perceived right (None without rows);
    ``folded``: up to shape twins (:func:`same_shapes`)."""
    key = "correct_folded" if folded else "correct"
    chosen = [r[key] for r in rows if r["channel"] == channel]
    return round(float(np.mean(chosen)), 3) if chosen else None


def _save_png(image: np.ndarray, path: Path) -> None:
    from PIL import Image

    Image.fromarray(np.asarray(image, dtype=np.uint8)).save(path)


def table2_markdown(
    rows: list[dict], family: str, voice: str, speed: float, backend: str, lexicon: list[str]
) -> str:
    """Table II in Markdown: one row per word and channel."""
    lines = [
        f"# Table II — words written by {family} from sound and from letter images",
        "",
        f"Sound: espeak-ng voice `{voice}` at {speed} wpm, recognised by "
        f"`{backend}` (lexicon: {list(lexicon or []) or 'none'}). "
        "Images: the first original test-split image of each letter; the model reads them "
        "(column *perceived*) and the word's spelling places the letters.",
        "",
        "| word | input | perceived | written | DMP RMSE (mm) | writing (s) | latency (s) |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['word']} | {r['channel']} | {r['perceived'] or '-'} | {r['written']} | "
            f"{r['dmp_rmse_mm']:.3f} | {r['duration_s']:.1f} | {r['seconds']:.2f} |"
        )
    lines += ["", "Figure: `table2.png`; per-word outputs and Rerun recordings in `<word>/`.", ""]
    return "\n".join(lines)


def table2_figure(words: list[str], channels: list[str], items: dict, path: Path) -> None:
    """Inputs (spectrogram or letter images) above, written words below, one column per case."""
    plt = pyplot()
    columns = [(w, c) for w in words for c in channels]
    fig, axes = plt.subplots(
        2, len(columns), figsize=(2.6 * len(columns), 3.4), squeeze=False, height_ratios=[1, 1]
    )
    for col, (word, channel) in enumerate(columns):
        top, bottom = axes[0, col], axes[1, col]
        source = items[word, channel]
        if channel == "sound":
            freqs, _, power = spectrogram(source, fs=SAMPLE_RATE, nperseg=256, noverlap=192)
            shown = freqs <= 6000
            decibels = 10 * np.log10(power[shown] + 1e-12)  # digital silence has zero power
            top.imshow(
                decibels,
                origin="lower",
                aspect="auto",
                cmap="magma",
                vmin=decibels.max() - 80,
                extent=(0, len(source) / SAMPLE_RATE, 0, freqs[shown][-1]),
            )
        else:
            top.imshow(np.concatenate(source, axis=1), cmap="gray", vmin=0, vmax=255)
        top.set_title(f"{word}: {channel}", fontsize=10)
        top.set_xticks([])
        top.set_yticks([])
        written: WordTrajectory = items[word, channel, "word"]
        for kind, segment in written.polylines(highlight=False):
            colour = {"letter": "black", "mark": hex_colour(MARK)}.get(kind, "tab:orange")
            bottom.plot(segment[:, 0], segment[:, 1], color=colour, linewidth=1.2)
        bottom.set_aspect("equal")
        bottom.axis("off")
    axes[0, 0].set_ylabel("input")
    axes[1, 0].set_ylabel("output")
    fig.suptitle("Words from sound (x_S) and from letter images (x_I)", fontsize=11)
    fig.tight_layout()
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=120)
    finally:
        plt.close(fig)
