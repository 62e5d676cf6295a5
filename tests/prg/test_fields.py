"""One declaration of a field's accepted values (prg.fields.ranged): the settings dataclass
refuses a value outside it, and the config check (prg.checks.RANGES) refuses the same value of
the option with the range taken from the same declaration."""

from __future__ import annotations

import dataclasses
import re
import subprocess
import sys

import pytest

from prg.checks import DECLARED, RANGES, TABLE, Range, check_values, count, range_of
from prg.errors import SettingsError, UsageError
from prg.evaluation.settings import (
    ClassifierSettings,
    CoherenceSettings,
    EvaluationSettings,
    LikelihoodSettings,
    LikenessSettings,
    StyleSettings,
)
from prg.export.settings import (
    ExportSettings,
    GcodeSettings,
    HpglSettings,
    LimitSettings,
    PlotterSettings,
)
from prg.fields import check_fields, declared_ranges, ranged
from prg.pipeline.settings import (
    ConnectionSettings,
    GenerateSettings,
    LayoutSettings,
    MarkSettings,
)
from prg.sim.settings import (
    Camera,
    ControlSettings,
    IKSettings,
    MotionSettings,
    Paper,
    RobotSettings,
)

SETTINGS = {
    "generate": GenerateSettings,
    "marks": MarkSettings,
    "layout": LayoutSettings,
    "connection": ConnectionSettings,
    "likelihood": LikelihoodSettings,
    "coherence": CoherenceSettings,
    "classifier": ClassifierSettings,
    "likeness": LikenessSettings,
    "styles": StyleSettings,
    "gcode": GcodeSettings,
    "hpgl": HpglSettings,
    "limits": LimitSettings,
    "paper": Paper,
    "motion": MotionSettings,
    "control": ControlSettings,
    "ik": IKSettings,
    "camera": Camera,
    "robot": RobotSettings,
}
# settings classes of a config node that declare no range: each of their numbers is kept in
# TABLE (IN_TABLE, AT_TOP), so the node is not in DECLARED
UNDECLARED = {"plotter": PlotterSettings}
# fields whose config option keeps its range in TABLE, node -> {field: option}: one held in
# another unit than its option, and those holding several numbers (checked item by item)
IN_TABLE = {
    "connection": {"alpha_max": "alpha_max_deg"},
    "coherence": {"temperatures": "temperatures.*", "image_shifts": "image_shifts"},
    "styles": {"ks": "ks", "seeds": "seeds"},
    "plotter": {"paper_mm": "paper_mm", "position_mm": "position_mm"},
    "gcode": {"origin_mm": "origin_mm"},
}
# fields whose option is a top-level key of TABLE read by several commands (as seed), node ->
# {field: key}; the class checks the field against TABLE's own entry
AT_TOP = {"plotter": {"scale": "scale"}}
# options under a declared node that its class does not hold, in TABLE: limits.joints, each
# robot's datasheet, read by prg.export.limits.JointLimits (vectors, one number per joint);
# paper.word_centre_cm, held by SimSettings (declared with TABLE's entry, WORD_CENTRE_CM)
BESIDE = {
    "limits": {f"joints.*.{q}" for q in ("lower", "upper", "velocity", "acceleration", "jerk")},
    "paper": {"word_centre_cm"},
}
# the settings classes of a whole command (their own fields: top-level keys, kept in TABLE)
TOP_LEVEL = {"prg-evaluate": EvaluationSettings, "prg-export": ExportSettings}


@dataclasses.dataclass(frozen=True)
class _Walk:
    steps: int = ranged(20, count(0, 1000))
    pace: float = ranged(1.0, Range(0, 10, low_open=True, optional=True))
    name: str = "walk"

    def __post_init__(self) -> None:
        check_fields(self)


def test_a_declared_range_is_enforced_by_the_dataclass_naming_the_field():
    assert _Walk().steps == 20 and _Walk(pace=None).pace is None
    with pytest.raises(SettingsError, match=r"^steps must be an integer in \[0, 1000\], got -1$"):
        _Walk(steps=-1)
    with pytest.raises(SettingsError, match=r"^pace must be a finite number in \(0, 10\] or null"):
        _Walk(pace=float("nan"))


def test_declared_ranges_are_the_ranged_fields_under_their_node():
    pace = Range(0, 10, low_open=True, optional=True)
    assert declared_ranges(_Walk) == {"steps": count(0, 1000), "pace": pace}
    assert set(declared_ranges(_Walk, "walk")) == {"walk.steps", "walk.pace"}


def test_the_declared_nodes_are_the_settings_classes():
    assert {node: getattr(sys.modules[m], c) for node, (m, c) in DECLARED.items()} == SETTINGS


@pytest.mark.parametrize("node", sorted(SETTINGS))
def test_the_config_check_takes_its_ranges_from_the_declarations(node):
    declared = declared_ranges(SETTINGS[node], node)
    assert declared and all(RANGES[key] is spec for key, spec in declared.items())
    kept = {f"{node}.{option}" for option in IN_TABLE.get(node, {}).values()}
    kept |= {f"{node}.{option}" for option in BESIDE.get(node, ())}
    in_table = {key for key in TABLE if key.startswith(f"{node}.")}
    assert in_table == kept  # written once, not twice


@pytest.mark.parametrize(
    "node, field, value",
    [
        ("generate", "impute_steps", -1),
        ("generate", "temperature", 11.0),
        ("generate", "hand_seed", 1.5),
        ("generate", "speed_cm_s", 0),
        ("marks", "dot_gap", 0.7),
        ("marks", "bar_height", float("inf")),
        ("layout", "gap", 0),
        ("layout", "letter_height", 101.0),
        ("connection", "max_steps", -1),
        ("connection", "home_radius", -1.0),
        ("connection", "theta_p", -0.5),
        ("likelihood", "traj_std", 0.0),
        ("likelihood", "n_test", 0),
        ("coherence", "impute_steps", 1001),
        ("classifier", "lr", 0),
        ("likeness", "n_per_class", 3),
        ("styles", "n_eval", 62),
        ("gcode", "decimals", 7),
        ("gcode", "z_feed_mm_min", 0),
        ("gcode", "max_feed_mm_min", 0.0),
        ("hpgl", "velocity", 101),
        ("limits", "max_slow_down", 0.5),
        ("limits", "compliance_mm", -1.0),
        ("paper", "thickness_m", 0.2),
        ("motion", "lift_cm", 0),
        ("control", "steps_per_waypoint", 0),
        ("ik", "residual", 2.0),
        ("camera", "fov", 171.0),
    ],
)
def test_one_range_refuses_a_value_in_the_dataclass_and_in_the_config(node, field, value):
    with pytest.raises(SettingsError) as in_class:
        SETTINGS[node](**{field: value})
    with pytest.raises(UsageError) as in_config:
        check_values({node: {field: value}})
    assert str(in_class.value.under(node)) == str(in_config.value)
    assert str(in_config.value).startswith(f"{node}.{field} must be ")


def _numeric(annotation: str) -> bool:
    """A field annotated (as text: ``from __future__ import annotations``) int or float."""
    return bool(re.search(r"\b(int|float)\b", annotation))


@pytest.mark.parametrize("node", sorted(SETTINGS | UNDECLARED))
def test_every_numeric_field_of_a_settings_class_declares_its_range_or_is_kept(node):
    cls = (SETTINGS | UNDECLARED)[node]
    numeric = {f.name for f in dataclasses.fields(cls) if _numeric(str(f.type))}
    kept = set(IN_TABLE.get(node, {})) | set(AT_TOP.get(node, {}))
    declared = {key.removesuffix(".*") for key in declared_ranges(cls)}  # keyed: NAME.*
    assert numeric and numeric - kept == declared
    assert (node in DECLARED) == bool(declared_ranges(cls))


def test_a_field_kept_in_the_table_is_checked_by_its_class_and_its_option_has_a_range():
    assert "check" in ConnectionSettings.__dataclass_fields__["alpha_max"].metadata
    for node, fields in IN_TABLE.items():
        for option in fields.values():
            key = f"{node}.{option}"
            assert range_of(key.replace("*", "x")) is TABLE[key]


def test_a_field_read_from_a_top_level_key_is_checked_against_that_keys_entry():
    for node, fields in AT_TOP.items():
        for name, key in fields.items():
            check = (SETTINGS | UNDECLARED)[node].__dataclass_fields__[name].metadata["check"]
            assert check.keywords == {"spec": TABLE[key]}
            assert f"{node}.{name}" not in RANGES  # no option of that name under the node


@pytest.mark.parametrize("command", sorted(TOP_LEVEL))
def test_a_commands_own_numbers_are_top_level_keys_declared_with_the_tables_entries(command):
    declared = declared_ranges(TOP_LEVEL[command])
    assert declared and all(TABLE[key] is spec for key, spec in declared.items())
    assert TOP_LEVEL[command] not in SETTINGS.values()  # no node: TABLE keeps the keys


def test_a_numeric_field_without_a_declaration_is_caught():
    @dataclasses.dataclass(frozen=True)
    class Careless:
        steps: int = ranged(20, count(0, 1000))
        pace: float = 1.0  # no range: the test above names it

    numeric = {f.name for f in dataclasses.fields(Careless) if _numeric(str(f.type))}
    assert numeric - set(declared_ranges(Careless)) == {"pace"}
    # ... and the config check has no range for its option
    assert range_of("walk.pace") is None


def test_reading_the_declared_ranges_imports_no_numpy():
    code = (
        "import sys; from prg.checks import range_of; "
        "assert range_of('generate.seed') is not None; print('numpy' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
