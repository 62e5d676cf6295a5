"""The paper's path as one library call: Perceive -> Represent -> Generate.

The model is loaded once; ``write`` takes ``text=``, ``audio=``, ``images=``,
``trajectories=`` or any subset (the doctested example is on :class:`Writer`)::

    writer = Writer.from_checkpoint("models/muse/model.ckpt")
    writer.write(text="hello").save("outputs/hello")

:meth:`Writer.write` takes any subset of the command's channels — the text (the S channel, as a
speech recogniser yields it), a sound file (recognised into that text), images of the letters (the
I channel) and pen trajectories of the letters (the T channel) — and returns a
:class:`WriteResult`: what was perceived, the decoded letters, the word trajectory with its fitted
:class:`~prg.pipeline.dmp.DMP`, the DMP's rollout and the time each stage took. The two halves
are public too: :meth:`Writer.perceive` (the channels to per-letter model inputs, and the word's
letters) and :meth:`Writer.generate` (decode the letters, lay them out, connect them, fit the DMP).
The simulated robot writes a result with :func:`prg.sim.simulate_word`.
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import torch

from prg.alphabet import text_to_labels
from prg.checks import check_text_length
from prg.data.hands import HandBank
from prg.errors import UsageError
from prg.files import staged_outputs
from prg.models.base import MultimodalVAE
from prg.models.checkpoint import load_model
from prg.models.modalities import IMAGE, LABEL, TRAJ
from prg.pipeline.compose import GenerateSettings, clean_text, compose_word
from prg.pipeline.decode import (
    check_inputs,
    decode_letters,
    infer_text,
    label_inputs,
    usable_inputs,
)
from prg.pipeline.hands import (
    Hand,
    decode_in_hand,
    decoder_bias,
    match_hand,
    nearest_components,
    random_hand,
    read_style,
    write_in_hand,
)
from prg.pipeline.perceive import (
    perceive_letter_images,
    perceive_trajectories,
    read_letter_images,
    read_trajectories,
)
from prg.pipeline.speech import SAMPLE_RATE, SpeechSettings
from prg.pipeline.word import WordTrajectory

if TYPE_CHECKING:
    from prg.pipeline.speech import Transcript
    from prg.recorder import RecorderProcess

log = logging.getLogger(__name__)

PathOrImages = str | os.PathLike | Sequence[np.ndarray]
PathOrStrokes = str | os.PathLike | Sequence[np.ndarray]


#: What :meth:`WriteResult.save` writes into a folder (and so owns there).
WORD_FILES = ("word.json", "word.png", "word.svg", "dmp_rollout.csv", "motion.csv", "word.rrd")


@dataclass(frozen=True)
class Perception:
    """What Perceive made of a command: the word's letters and the per-letter model inputs.

    Attributes
    ----------
    text : str
        The letters to write (spaces between words): typed, heard, or read by the model.
    inputs : dict of str to Tensor
        Per-letter model inputs, one row per non-space letter: ``label`` (S), ``image`` (I),
        ``traj`` (T) — the channels given.
    read : str or None
        The word the model read from the images and/or trajectories (S given them), when it was
        asked to read (no text given, or :meth:`Writer.perceive` with ``read=True``).
    transcript : Transcript or None
        What the speech recogniser heard, for a command given as sound.
    audio : ndarray or None
        The sound's 16 kHz mono samples (for the recording).
    seconds : float
        Time spent perceiving (speech recognition, image and trajectory processing, reading).
    """

    text: str
    inputs: dict[str, torch.Tensor]
    read: str | None = None
    transcript: Transcript | None = None
    audio: np.ndarray | None = None
    seconds: float = 0.0


@dataclass
class WriteResult:
    """A word written by :meth:`Writer.write`.

    Attributes
    ----------
    perception : Perception
    settings : GenerateSettings
        The settings the word was generated with.
    family : str
        The model family that decoded the letters.
    letters : ndarray, shape (N, 100, 2)
        The decoded letters, normalised (y up), one per non-space letter.
    word : WordTrajectory
        Points and segments (letters, connection strokes, spaces, then the delayed strokes:
        i/j dots, t/f bars) in centimetres, its timing and the DMP fitted to its cursive body
        (``word.dmp``).
    rollout : ndarray, shape (n, 2)
        The DMP's rollout on ``linspace(0, word.dmp.tau, n)`` (the body: the delayed strokes
        follow it, :func:`prg.pipeline.motion.word_samples` gives the whole motion).
    timings : dict of str to float
        Seconds: ``perceive``, ``decode`` (the model), ``compose`` (layout, connection strokes,
        DMP fit) and ``total``.
    """

    perception: Perception
    settings: GenerateSettings
    family: str
    letters: np.ndarray
    word: WordTrajectory
    rollout: np.ndarray
    timings: dict[str, float] = field(default_factory=dict)

    @property
    def text(self) -> str:
        return self.word.text

    def save(
        self,
        folder: str | os.PathLike,
        record: bool = False,
        recorder: RecorderProcess | None = None,
    ) -> Path:
        """``word.json``, ``word.png``, ``word.svg``, ``dmp_rollout.csv`` (the body's DMP
        rollout), ``motion.csv`` (the whole timed pen motion, delayed strokes included, with its
        pen-down flag: :func:`prg.pipeline.motion.word_samples` at ``settings.samples_per_s``) and
        (``record``) the Rerun recording ``word.rrd`` into ``folder``, all or nothing (through a
        staging folder; other files already in ``folder`` are kept, but a ``word.rrd`` left
        by an earlier word is removed when ``record`` is off). With a ``recorder``
        (:class:`prg.recorder.RecorderProcess`, started before the model was loaded) the
        recording is made there, while this process writes the other files."""
        from prg.pipeline.motion import word_samples

        folder = Path(folder)
        with staged_outputs(folder, owned=WORD_FILES) as staging:
            self.word.to_json(staging / "word.json")
            if record and recorder is not None:
                recorder.send(staging, self.rollout, self.recording_inputs())
            elif record:
                self.record(staging / "word.rrd")
            self.word.to_png(staging / "word.png")
            self.word.to_svg(staging / "word.svg")
            t = np.linspace(0.0, self.word.dmp.tau, len(self.rollout))
            np.savetxt(
                staging / "dmp_rollout.csv",
                np.column_stack([t, self.rollout]),
                delimiter=",",
                header="t_s,x_cm,y_cm",
                comments="",
                fmt="%.6f",
            )
            xy, t, down = word_samples(self.word, 1.0 / self.settings.samples_per_s)
            np.savetxt(
                staging / "motion.csv",
                np.column_stack([t, xy, down]),
                delimiter=",",
                header="t_s,x_cm,y_cm,pen_down",
                comments="",
                fmt=["%.6f", "%.6f", "%.6f", "%d"],
            )
            if record and recorder is not None:
                recorder.wait()
        return folder

    def recording_inputs(self) -> dict[str, Any]:
        """What the recording shows besides the word and its rollout: the decoded ``letters``,
        the letter ``images`` and the heard ``audio``, ``sample_rate`` and ``transcript``
        (those given)."""
        seen = self.perception
        images = seen.inputs.get(IMAGE)
        inputs: dict[str, Any] = {
            "letters": self.letters,
            "images": None if images is None else images.numpy(),
        }
        if seen.transcript is not None:
            inputs |= {
                "audio": seen.audio,
                "sample_rate": SAMPLE_RATE,
                "transcript": seen.transcript.text,
            }
        return inputs

    def record(self, path: str | os.PathLike) -> Path:
        """The Rerun recording of the word, its inputs and its DMP rollout
        (:func:`prg.recording.record_write`)."""
        from prg.recording import record_write

        return record_write(path, self.word, self.rollout, **self.recording_inputs())


class Writer:
    """A trained multimodal VAE that writes words (the paper's Perceive, Represent, Generate).

    Parameters
    ----------
    model : MultimodalVAE
        A trained model (:meth:`from_checkpoint` loads one).
    settings : GenerateSettings, optional
        Decoding, layout, connection strokes, timing and DMP (``conf/write.yaml``'s defaults).
    speech : SpeechSettings, optional
        The speech recogniser for ``audio=``.
    on_unknown : {"error", "skip"}
        Characters outside 0-9, A-Z, a-z in a typed or heard text: one error, or dropped.
    hands : HandBank, optional
        The training writers' letters (a checkpoint's, :meth:`from_checkpoint`): what the
        default ``hand`` decoding draws letters from (:mod:`prg.pipeline.hands`).
    style : path or (trajectories, text), optional
        A person's letters to write in their hand: a style file (:func:`read_style`: a
        capture-page recording, a UJI-format file or an ``.npz``) or their normalised
        trajectories ``(k, 200)`` and their ``k`` letters. Every word is then written in that
        hand: the person's own letters for the classes they gave, the nearest training
        writer's for the rest.

    Examples
    --------
    With a model trained by ``make demo`` (any checkpoint of ``prg-train``):

    >>> from prg import Writer
    >>> writer = Writer.from_checkpoint("models/muse/model.ckpt")
    >>> result = writer.write(text="hello")
    >>> result.text, result.letters.shape
    ('hello', (5, 100, 2))
    >>> kinds = set(result.word.segment_kinds)  # the letters and the strokes joining them
    >>> sorted(kinds & {"letter", "connection"})
    ['connection', 'letter']
    >>> bool(result.word.duration_s > 0) and result.word.dmp.n_basis > 0
    True
    """

    def __init__(
        self,
        model: MultimodalVAE,
        settings: GenerateSettings | None = None,
        speech: SpeechSettings | None = None,
        on_unknown: str = "error",
        hands: HandBank | None = None,
        style: str | os.PathLike | tuple[np.ndarray, str] | None = None,
    ):
        _check_on_unknown(on_unknown)
        self.model = model.eval()
        self.settings = settings or GenerateSettings()
        self.speech = speech or SpeechSettings()
        self.on_unknown = on_unknown
        self.hands = hands
        self._bias: np.ndarray | None = None
        self.hand: Hand | None = None
        if style is not None:
            self.hand = match_hand(self._bank("style="), *_style_letters(style))
        # letter trajectories decoded from a label alone, by (label, impute_steps): see _decode
        self._label_letters: dict[tuple[int, int], np.ndarray] = {}

    @classmethod
    def from_checkpoint(cls, path: str | os.PathLike, **kwargs: Any) -> Writer:
        """A writer with the model of the checkpoint ``path`` (``models/<family>/model.ckpt``, or
        a training checkpoint); ``kwargs`` as :class:`Writer`."""
        _check_on_unknown(kwargs.get("on_unknown", "error"))  # before the model loads
        model, info = load_model(path)
        kwargs.setdefault("hands", info.get("hands"))
        return cls(model, **kwargs)

    def _bank(self, wanted: str) -> HandBank:
        if self.hands is None:
            raise UsageError(
                f"{wanted} needs the training writers' letters, which this model's checkpoint "
                "lacks (saved before they were kept): retrain it, or write with "
                "generate.mode=posterior"
            )
        return self.hands

    @property
    def family(self) -> str:
        return self.model.family

    def write(
        self,
        text: str | None = None,
        audio: str | os.PathLike | None = None,
        images: PathOrImages | None = None,
        trajectories: PathOrStrokes | None = None,
    ) -> WriteResult:
        """Write a word given through any subset of channels (:meth:`perceive`, then
        :meth:`generate`). Without ``text`` or ``audio`` the model reads the letters from the
        images and/or trajectories."""
        return self.generate(self.perceive(text, audio, images, trajectories))

    def perceive(
        self,
        text: str | None = None,
        audio: str | os.PathLike | None = None,
        images: PathOrImages | None = None,
        trajectories: PathOrStrokes | None = None,
        spelling: str | None = None,
        read: bool = False,
    ) -> Perception:
        """Perceive: each channel split into per-letter model inputs, and the word's letters.

        Parameters
        ----------
        text : str, optional
            The word (the S channel).
        audio : path, optional
            A sound file of the spoken word (WAV, FLAC, ...), recognised into the text.
        images : path or sequence of ndarray, optional
            An image of the word (its letters apart), a folder of letter images, or one image
            per letter (any size, dark on light or light on dark).
        trajectories : path or sequence of ndarray, optional
            A JSON file of per-letter strokes (:func:`prg.pipeline.perceive.read_trajectories`)
            or one ``(n, 2)`` pen stroke per letter (y up, any scale).
        spelling : str, optional
            The word's known letters, for the layout only (not a model input): the images and/or
            trajectories are the model's only inputs (the paper's Table II from images).
        read : bool
            Let the model read the letters from the images/trajectories even when the text or the
            spelling is given (``Perception.read``; None when the family cannot read letters).
        """
        if text is not None and audio is not None:
            raise UsageError(
                "text and audio both give the S channel (the word's letters): give one of them"
            )
        if all(channel is None for channel in (text, audio, images, trajectories)):
            raise UsageError(
                "nothing to write: give text=WORD, audio=SOUND, images=PATH and/or "
                "trajectories=JSON"
            )
        if spelling is not None and (text is not None or audio is not None):
            raise UsageError(
                "a spelling places the letters of images= or trajectories=: give it "
                "without text= or audio="
            )
        start = time.perf_counter()
        transcript = samples = None
        if text is not None:
            if not text.strip():
                raise UsageError("text is empty: give the word to write, e.g. text=hello")
            text = clean_text(text, self.on_unknown)
        if audio is not None:  # before anything else: a bad recording fails fast
            transcript, samples = self._hear(audio)
            text = clean_text(transcript.word, self.on_unknown)
        inputs = label_inputs(text) if text is not None else {}
        if images is not None:
            inputs[IMAGE] = image_inputs(images)
        if trajectories is not None:
            inputs[TRAJ] = trajectory_inputs(trajectories)
        model_read = None
        if text is None and spelling is None:
            model_read = self.read(inputs)
            text = check_text_length(model_read, "the word read from images=/trajectories=")
        elif read and LABEL in self.model.generated_modalities:
            model_read = self.read(inputs)
        if model_read is not None:
            log.info("read %r from the images/trajectories", model_read)
        if spelling is not None:
            text = clean_text(spelling, self.on_unknown, key="spelling")
        return Perception(
            text=text,
            inputs=inputs,
            read=model_read,
            transcript=transcript,
            audio=samples,
            seconds=time.perf_counter() - start,
        )

    def read(self, inputs: dict[str, torch.Tensor]) -> str:
        """The letters the model reads from per-letter inputs (S given them; needs a family that
        generates labels)."""
        return infer_text(self.model, {m: x for m, x in inputs.items() if m != LABEL})

    def generate(self, perception: Perception) -> WriteResult:
        """Represent and Generate: decode a trajectory per letter, then size, place and connect
        the letters and fit one DMP to the whole word."""
        check_inputs(perception.text, perception.inputs)
        settings = self.settings
        start = time.perf_counter()
        letters = self._decode(perception.inputs, perception.text)
        decoded = time.perf_counter()
        word, rollout = compose_word(letters, perception.text, settings)
        composed = time.perf_counter()
        timings = {
            "perceive": perception.seconds,
            "decode": decoded - start,
            "compose": composed - decoded,
        }
        timings["total"] = sum(timings.values())
        return WriteResult(perception, settings, self.family, letters, word, rollout, timings)

    def _decode(self, inputs: dict[str, torch.Tensor], text: str) -> np.ndarray:
        """One trajectory per letter: in a hand (:func:`decode_in_hand`), or decoded from the
        command's posterior (:func:`decode_letters`)."""
        settings = self.settings
        if settings.mode == "posterior":
            return self._decode_posterior(inputs)
        bank = self._bank("generate.mode=hand")
        labels = np.asarray(text_to_labels(text.replace(" ", "")), dtype=np.int64)
        shown = {m: x for m, x in inputs.items() if m != LABEL}
        if shown and self.hand is None:  # letters shown as images or pen strokes keep their shape
            usable = usable_inputs(self.model, inputs)
            if set(usable) != {LABEL}:
                chosen = nearest_components(self.model, bank, usable, labels)
                s = settings
                return decode_in_hand(
                    self.model, chosen, labels, s.hand_temperature, s.seed, self._decoder_bias()
                )
        hand_seed = settings.seed if settings.hand_seed is None else settings.hand_seed
        hand = self.hand or random_hand(bank, hand_seed)
        return write_in_hand(
            self.model,
            bank,
            hand,
            labels,
            settings.hand_temperature,
            settings.seed,
            self._decoder_bias(),
        )

    def _decoder_bias(self) -> np.ndarray:
        """:func:`decoder_bias`, estimated once per writer (about 70 ms for the demo's 5,208
        letters)."""
        if self._bias is None:
            self._bias = decoder_bias(self.model, self._bank("generate.mode=hand"))
        return self._bias

    def _decode_posterior(self, inputs: dict[str, torch.Tensor]) -> np.ndarray:
        """One trajectory per letter (:func:`decode_letters`).

        A letter given by its label alone and decoded at temperature 0 is a function of the
        model, the label and ``impute_steps`` only, so a writer decodes it once and reuses it:
        a warm writer's second word costs the layout and the DMP, not the model. The labels not
        yet seen are decoded together, so a letter's trajectory can differ in float32 rounding
        (about 1e-6 of the letter's size) from the same letter decoded in another batch."""
        settings = self.settings
        if set(inputs) != {LABEL} or settings.temperature != 0:
            return decode_letters(
                self.model, inputs, settings.temperature, settings.seed, settings.impute_steps
            )
        keys = [(int(label), settings.impute_steps) for label in inputs[LABEL]]
        missing = list(dict.fromkeys(k for k in keys if k not in self._label_letters))
        if missing:
            labels = torch.tensor([label for label, _ in missing], dtype=inputs[LABEL].dtype)
            new = decode_letters(
                self.model, {LABEL: labels}, 0.0, settings.seed, settings.impute_steps
            )
            self._label_letters.update(zip(missing, new, strict=True))
        return np.stack([self._label_letters[k] for k in keys])

    def _hear(self, audio: str | os.PathLike) -> tuple[Transcript, np.ndarray]:
        from prg.pipeline.speech import load_audio, perceive_speech

        samples = load_audio(audio, max_seconds=self.speech.max_seconds)
        _, transcript = perceive_speech(samples, self.speech, SAMPLE_RATE, name=str(audio))
        log.info("heard %r (%s) in %.2f s", transcript.word, transcript.backend, transcript.seconds)
        return transcript, samples


def _check_on_unknown(on_unknown: str) -> None:
    if on_unknown not in ("error", "skip"):
        raise UsageError(f"on_unknown {on_unknown!r}: choose error or skip")


def _style_letters(
    style: str | os.PathLike | tuple[np.ndarray, str],
) -> tuple[np.ndarray, np.ndarray]:
    """A style's normalised trajectories and classes: from a file, or given as arrays."""
    if isinstance(style, str | os.PathLike):
        return read_style(style)
    traj, letters = style
    traj = np.asarray(traj, dtype=np.float32)
    if traj.ndim != 2 or traj.shape[1] != 200 or len(traj) != len(letters) or not len(traj):
        raise UsageError(
            f"style: {traj.shape} trajectories for {len(letters)} letters; accepted are "
            "(k, 200) normalised trajectories and their k letters, k >= 1"
        )
    return traj, np.asarray(text_to_labels(letters), dtype=np.int64)


def image_inputs(images: PathOrImages) -> torch.Tensor:
    """The I channel: a word image or a folder of letter images (a path), or letter images."""
    if isinstance(images, str | os.PathLike):
        images = read_letter_images(images)
    return torch.from_numpy(perceive_letter_images(images))


def trajectory_inputs(trajectories: PathOrStrokes) -> torch.Tensor:
    """The T channel: a JSON file of strokes (a path), or one ``(n, 2)`` stroke per letter."""
    y_down = False
    if isinstance(trajectories, str | os.PathLike):
        trajectories, y_down = read_trajectories(trajectories)
    return torch.from_numpy(perceive_trajectories(trajectories, y_down=y_down))
