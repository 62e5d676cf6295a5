"""The ``pocketsphinx`` back-end: CMU PocketSphinx 5.

PocketSphinx 5 with its shipped US English acoustic model, dictionary (CMUdict) and language
model. With a lexicon it decodes with a JSGF grammar that accepts exactly one lexicon entry
(pronunciations from the dictionary); a lexicon word missing from the dictionary is an error
naming it (a grammar cannot contain a word it cannot pronounce, and silently dropping it would
make that word unrecognisable). ``model``: a folder with an acoustic model; a ``*.dict`` and
``*.lm.bin`` in it replace the shipped ones. Cepstral mean normalisation runs per utterance
(``cmn=batch``), so results do not depend on earlier calls; the lattice best-path pass is off
(``bestpath=False``): with 5.1.1 it returned empty hypotheses for most short grammar utterances
(measured on espeak-ng words).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from prg.errors import UsageError
from prg.pipeline.speech.dependencies import first_line, needs
from prg.pipeline.speech.settings import SpeechSettings


class PocketSphinxRecogniser:
    """PocketSphinx 5: default English LM, or a JSGF grammar of the lexicon."""

    backend = "pocketsphinx"

    def __init__(self, model: str | None) -> None:
        with needs("pocketsphinx", self.backend):
            from pocketsphinx import Decoder
        options: dict[str, Any] = {"loglevel": "FATAL", "cmn": "batch", "bestpath": False}
        if model is not None:
            folder = Path(model).expanduser()
            if not folder.is_dir():
                raise UsageError(f"speech model folder {model!r} (pocketsphinx) does not exist")
            options["hmm"] = str(folder)
            for key, pattern in (("dict", "*.dict"), ("lm", "*.lm.bin")):
                found = sorted(folder.glob(pattern))
                if found:
                    options[key] = str(found[0])
        self.model = model or "pocketsphinx en-us (shipped)"
        try:
            self.decoder = Decoder(**options)
        except (RuntimeError, ValueError, KeyError) as err:
            raise UsageError(
                f"pocketsphinx model {model!r} cannot be loaded: {first_line(err)}"
            ) from None
        self._default_search = self.decoder.current_search()
        self._grammars: dict[tuple[str, ...], str] = {}

    def missing_words(self, lexicon: Sequence[str]) -> list[str]:
        """Lexicon entries with a word the pronouncing dictionary lacks."""
        return [
            entry
            for entry in lexicon
            if any(self.decoder.lookup_word(w) is None for w in entry.lower().split())
        ]

    def _search(self, lexicon: tuple[str, ...] | None) -> str:
        if lexicon is None:
            return self._default_search
        if lexicon not in self._grammars:
            missing = self.missing_words(lexicon)
            if missing:
                shown = ", ".join(repr(w) for w in missing)
                raise UsageError(
                    f"lexicon words {shown} are not in the pocketsphinx dictionary: accepted "
                    "are words of its pronouncing dictionary (CMUdict, US English)"
                )
            name = f"lexicon{len(self._grammars)}"
            alternatives = " | ".join(entry.lower() for entry in lexicon)
            grammar = f"#JSGF V1.0;\ngrammar {name};\npublic <word> = {alternatives} ;\n"
            self.decoder.add_jsgf_string(name, grammar)
            self._grammars[lexicon] = name
        return self._grammars[lexicon]

    def transcribe(self, audio: np.ndarray, params: SpeechSettings) -> str:
        self.decoder.activate_search(self._search(params.lexicon))
        pcm = (np.clip(audio, -1.0, 1.0) * 32767.0).astype("<i2").tobytes()
        self.decoder.start_utt()
        self.decoder.process_raw(pcm, full_utt=True)
        self.decoder.end_utt()
        hyp = self.decoder.hyp()
        return hyp.hypstr if hyp is not None else ""

    def score(self, audio: np.ndarray, words: Sequence[str], params: SpeechSettings) -> np.ndarray:
        raise UsageError("rescore is for whisper and wav2vec2, not pocketsphinx")
