"""The ``wav2vec2`` back-end, the paper's recogniser.

``transformers`` ``Wav2Vec2ForCTC`` with its processor, greedy CTC decoding. ``model``: a local
folder or a hub id in the local cache (``local_files_only``). Default:
``facebook/wav2vec2-base-960h``. With a lexicon: snapping, or with ``rescore=True`` the lexicon
word of highest CTC log-likelihood (``torch.nn.functional.ctc_loss``, exact).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from prg.errors import UsageError
from prg.pipeline.speech.audio import SAMPLE_RATE
from prg.pipeline.speech.backends.base import model_source, not_cached
from prg.pipeline.speech.dependencies import needs
from prg.pipeline.speech.settings import SpeechSettings

DEFAULT_WAV2VEC2 = "facebook/wav2vec2-base-960h"


class Wav2Vec2Recogniser:
    """``Wav2Vec2ForCTC`` + processor, greedy CTC decoding, CTC-likelihood scoring."""

    backend = "wav2vec2"

    def __init__(self, model: str | None) -> None:
        with needs("transformers", self.backend):
            import torch  # noqa: F401
            from transformers import AutoProcessor, Wav2Vec2ForCTC
        model = DEFAULT_WAV2VEC2 if model is None else model
        source = model_source(model, self.backend)
        self.model = model
        try:
            self.processor = AutoProcessor.from_pretrained(source, local_files_only=True)
            # safetensors only: a pickled pytorch_model.bin could run code when loaded
            self.network = Wav2Vec2ForCTC.from_pretrained(
                source, local_files_only=True, use_safetensors=True
            ).eval()
        except (OSError, ValueError) as err:
            raise not_cached(self.backend, model, "a local model folder", err) from None
        rate = getattr(getattr(self.processor, "feature_extractor", None), "sampling_rate", None)
        if rate != SAMPLE_RATE:
            raise UsageError(
                f"wav2vec2 model {model!r} expects {rate} Hz audio: accepted are 16000 Hz models"
            )

    def _log_probs(self, audio: np.ndarray):
        import torch

        inputs = self.processor(audio, sampling_rate=SAMPLE_RATE, return_tensors="pt")
        with torch.inference_mode():
            logits = self.network(inputs.input_values).logits
        return torch.log_softmax(logits.float(), dim=-1)[0]  # (frames, vocab)

    def transcribe(self, audio: np.ndarray, params: SpeechSettings) -> str:
        ids = self._log_probs(audio).argmax(dim=-1)
        return self.processor.batch_decode(ids[None], skip_special_tokens=True)[0]

    def score(self, audio: np.ndarray, words: Sequence[str], params: SpeechSettings) -> np.ndarray:
        """CTC log-likelihood of each word's characters (-inf if the vocabulary lacks one)."""
        import torch

        tokenizer = self.processor.tokenizer
        vocab = tokenizer.get_vocab()
        upper = "A" in vocab and "a" not in vocab
        delimiter = tokenizer.word_delimiter_token
        blank = tokenizer.pad_token_id
        log_probs = self._log_probs(audio)
        scores = np.full(len(words), -np.inf)
        for i, word in enumerate(words):
            chars = [
                delimiter if c == " " else c for c in (word.upper() if upper else word.lower())
            ]
            if not chars or any(c not in vocab for c in chars):
                continue
            target = torch.tensor([[vocab[c] for c in chars]])
            loss = torch.nn.functional.ctc_loss(
                log_probs[:, None, :],
                target,
                torch.tensor([log_probs.shape[0]]),
                torch.tensor([len(chars)]),
                blank=blank,
                reduction="sum",
                zero_infinity=False,
            )
            scores[i] = -float(loss)
        return scores
