"""The settings of writing a word (prg.pipeline.settings): the classes the pipeline modules export,
importable without numpy so that the config check can read their declared ranges first."""

from __future__ import annotations

import subprocess
import sys

import pytest

from prg.errors import SettingsError
from prg.pipeline import compose, marks, settings
from prg.pipeline.connect import ConnectionSettings
from prg.pipeline.layout import LayoutSettings


def test_the_pipeline_modules_export_the_same_classes():
    assert compose.GenerateSettings is settings.GenerateSettings
    assert marks.MarkSettings is settings.MarkSettings
    assert compose.DECODING_MODES == settings.DECODING_MODES == ("hand", "posterior")


def test_the_nested_settings_default_to_their_classes():
    generate = settings.GenerateSettings()
    assert generate.layout == LayoutSettings() and generate.connection == ConnectionSettings()
    assert generate.marks == settings.MarkSettings()


def test_the_marks_still_refuse_letters_outside_the_alphabet():
    with pytest.raises(SettingsError, match=r"^dotted '!': give letters from 0-9, A-Z, a-z$"):
        settings.MarkSettings(dotted="!")


def test_the_module_imports_no_numpy():
    code = "import sys, prg.pipeline.settings; print('numpy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
