"""Settings built in Python refuse what the commands refuse: SpeechSettings' every number against
its ``speech.*`` config range, its language and its flags; GenerateSettings' nested settings."""

from __future__ import annotations

import math

import pytest

from prg.checks import TABLE
from prg.errors import SettingsError
from prg.pipeline.settings import GenerateSettings, LayoutSettings
from prg.pipeline.speech import SpeechSettings
from prg.pipeline.speech.settings import LANGUAGES

SPEECH_RANGES = {k.removeprefix("speech."): v for k, v in TABLE.items() if k.startswith("speech.")}


def refused_values(spec) -> list:
    """Values the config check refuses for ``spec``: past each bound, a string, a bool."""
    values = ["3", True]
    if spec.high is not None and spec.high < math.inf:
        values.append(spec.high + 1)
    if spec.low is not None and spec.low > -math.inf:
        values.append(spec.low - 1)
    return values


@pytest.mark.parametrize("field", sorted(SPEECH_RANGES))
def test_every_number_refused_by_the_command_is_refused_by_the_class(field):
    spec = SPEECH_RANGES[field]
    for value in refused_values(spec):
        assert not spec.accepts(value) or isinstance(value, str | bool)
        with pytest.raises(SettingsError) as refused:
            SpeechSettings(**{field: value})
        assert str(refused.value).startswith(field), refused.value


def test_the_table_covers_every_number_of_the_class():
    numbers = {"prior_weight", "slowdown", "view_margin", "min_lead", "noise_subtraction"}
    assert numbers | {"max_seconds", "min_rms_dbfs", "beam_size"} == set(SPEECH_RANGES)


def test_view_margin_may_still_be_infinite_in_python():
    assert SpeechSettings(view_margin=math.inf).view_margin == math.inf


@pytest.mark.parametrize("language", ["klingon", "EN", "", 3, None])
def test_unknown_language_is_refused_naming_the_codes(language):
    with pytest.raises(SettingsError, match=r"^language .* is unknown: accepted are whisper"):
        SpeechSettings(language=language)


def test_known_languages_are_accepted():
    assert "en" in LANGUAGES and "yue" in LANGUAGES and len(LANGUAGES) == len(set(LANGUAGES))
    for language in ("en", "fr", "zh"):
        assert SpeechSettings(language=language).language == language


def test_rescore_must_be_a_boolean():
    with pytest.raises(SettingsError, match="rescore must be true or false, got 'yes'"):
        SpeechSettings(rescore="yes", lexicon=["bell"])


@pytest.mark.parametrize(
    "field, value",
    [("marks", "dots"), ("layout", None), ("connection", {}), ("layout", {"x": 1})],
)
def test_generate_settings_refuse_a_nested_settings_of_another_type(field, value):
    with pytest.raises(SettingsError, match=f"^{field} must be a "):
        GenerateSettings(**{field: value})


def test_generate_settings_keep_their_nested_settings():
    layout = LayoutSettings()
    assert GenerateSettings(layout=layout).layout is layout
