"""The settings of an export (prg.export.settings): the classes the export modules export,
importable without numpy so that prg-export checks its config against their declared ranges
first; prg.export itself imports its numpy modules on first use."""

from __future__ import annotations

import subprocess
import sys

import pytest

from prg.checks import TABLE, check_values
from prg.errors import SettingsError, UsageError
from prg.export import limits, plotter, run, settings
from prg.fields import declared_ranges


def _modules_after(code: str) -> str:
    probe = (
        f"import sys; {code}; print(sorted({{'numpy', 'prg.export.plotter'}} & set(sys.modules)))"
    )
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    return out.stdout.strip()


def test_the_export_modules_export_the_same_classes():
    assert plotter.PlotterSettings is settings.PlotterSettings
    assert plotter.GcodeSettings is settings.GcodeSettings
    assert plotter.HpglSettings is settings.HpglSettings
    assert limits.LimitSettings is settings.LimitSettings
    assert run.ExportSettings is settings.ExportSettings
    assert run.FILES is settings.FILES and run.FORMATS == settings.FORMATS


def test_the_module_and_the_package_import_no_numpy():
    assert _modules_after("import prg.export.settings") == "[]"
    assert _modules_after("from prg.export import ExportSettings, LimitSettings") == "[]"


def test_every_name_of_the_package_is_its_modules_and_is_imported_on_first_use():
    import prg.export

    for name in prg.export.__all__:
        value = getattr(prg.export, name)
        assert value is getattr(sys.modules[f"prg.export.{prg.export._MODULES[name]}"], name)
    assert set(prg.export.__all__) <= set(dir(prg.export))
    with pytest.raises(AttributeError, match="has no attribute 'nothing'"):
        prg.export.nothing  # noqa: B018
    assert "'numpy'" in _modules_after("from prg.export import export_word")


@pytest.mark.parametrize(
    "cls, values, message",
    [
        (settings.PlotterSettings, {"paper_mm": (0, 210)}, r"^paper_mm\[0\] must be a finite"),
        (settings.PlotterSettings, {"paper_mm": (1, 2, 3)}, r"^paper_mm must be two positive"),
        (settings.PlotterSettings, {"scale": 0}, r"^scale must be a finite number in \(0, 1000\]"),
        (settings.GcodeSettings, {"origin_mm": (0, 1e5)}, r"^origin_mm\[1\] must be "),
        (settings.GcodeSettings, {"decimals": 7}, r"^decimals must be an integer in \[2, 6\]"),
        (settings.GcodeSettings, {"z_up_mm": -1.0}, r"^z_up_mm must be above z_down_mm \(0\)"),
        (settings.HpglSettings, {"velocity": 0}, r"^velocity must be an integer in \[1, 100\]"),
        (settings.LimitSettings, {"max_slow_down": 0.5}, r"^max_slow_down must be a finite"),
        (settings.ExportSettings, {"sample_dt_s": 0}, r"^sample_dt_s must be a finite number"),
        (settings.ExportSettings, {"tempo": 11}, r"^tempo must be a finite number in \(0, 10\]"),
    ],
)
def test_each_class_refuses_its_bad_values_naming_the_field(cls, values, message):
    with pytest.raises(SettingsError, match=message):
        cls(**values)


def test_the_top_level_numbers_are_checked_against_the_tables_own_entries():
    assert declared_ranges(settings.ExportSettings) == {
        "tempo": TABLE["tempo"],
        "sample_dt_s": TABLE["sample_dt_s"],
    }
    with pytest.raises(UsageError, match=r"^sample_dt_s must be a finite number in \(0, 0.1\]"):
        check_values({"sample_dt_s": 0.5})
    with pytest.raises(SettingsError) as in_class:
        settings.PlotterSettings(scale=2000)
    with pytest.raises(UsageError) as in_config:
        check_values({"scale": 2000})
    assert str(in_class.value) == str(in_config.value)


def test_the_defaults_are_the_configs():
    export = settings.ExportSettings()
    assert export.formats == ("gcode", "hpgl", "svg", "mcap", "csv")
    assert export.plotter.paper_mm == (297.0, 210.0) and export.gcode.origin_mm == (0.0, 0.0)
    assert export.limits.max_slow_down == 4.0 and export.hpgl.velocity is None
