"""The simulator's settings (prg.sim.settings): library defaults are the config's, one typed
boundary (:meth:`SimSettings.from_mapping`) whose errors name the field and its place, and each
range declared once: the dataclass and ``prg-simulate`` refuse the same value with the same line
(no numpy, no PyBullet)."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from dataclasses import replace

import pytest

from prg.checks import DECLARED, RANGES, TABLE, Range, check_values
from prg.errors import SettingsError, UsageError
from prg.fields import declared_ranges
from prg.sim import (
    Camera,
    ControlSettings,
    IKSettings,
    MotionSettings,
    Paper,
    RobotSettings,
    SimSettings,
)
from tests.conftest import BIN, run_cli
from tests.helpers.sim_settings import CONF, _yaml

# the config nodes of prg-simulate whose ranges their settings class declares
NODES = {
    "paper": Paper,
    "motion": MotionSettings,
    "control": ControlSettings,
    "ik": IKSettings,
    "camera": Camera,
    "robot": RobotSettings,
}
PANDA = _yaml(CONF / "robot" / "panda.yaml")


def test_the_library_defaults_are_conf_simulate_yaml():
    config = _yaml(CONF / "simulate.yaml")
    settings = SimSettings.from_mapping(config)
    assert settings == SimSettings()
    assert settings.paper.size_cm == tuple(config["paper"]["size_cm"])
    assert settings.word_centre_cm == tuple(config["paper"]["word_centre_cm"])
    assert settings.control.time_step == config["control"]["time_step"]


@pytest.mark.parametrize(
    ("section", "key", "value", "message"),
    [
        ("motion", "lift_cm", 0, r"motion.lift_cm must be a finite number in \(0, 100\], got 0$"),
        ("motion", "dwell_s", -1.0, r"motion.dwell_s must be a finite number in \[0, 60\]"),
        (
            "control",
            "time_step",
            -0.01,
            r"control.time_step must be a finite number in \(0, 0.05\]",
        ),
        ("control", "steps_per_waypoint", 2.5, r"control.steps_per_waypoint must be an integer"),
        ("control", "position_gain", "x", r"control.position_gain must be a finite .*, got 'x'"),
        ("ik", "method", "fast", "ik.method 'fast': choose refined, null_space, plain"),
        ("ik", "cold_iterations", True, r"ik.cold_iterations must be an integer .*, got True"),
        ("camera", "width", 0, r"camera.width must be an integer in \[16, 8192\], got 0"),
        ("camera", "fov", 200.0, r"camera.fov must be a finite number in \[1, 170\]"),
        ("paper", "size_cm", [0, 29.7], r"paper.size_cm\[0\] must be a finite number in \(0, "),
        ("paper", "size_cm", [1.0], r"paper.size_cm must be a list of 2 numbers, got \(1.0,\)"),
        ("paper", "thickness_m", 0, r"paper.thickness_m must be a finite number in \(0, 0.1\]"),
        ("paper", "word_centre_cm", [1.0], r"paper.word_centre_cm must be a list of 2 numbers"),
        (None, "word_centre_cm", [1.0], r"^word_centre_cm must be a list of 2 numbers"),
        (None, "scale", 0, r"^scale must be a finite number in \(0, 1000\], got 0"),
        (None, "tempo", float("inf"), r"^tempo must be a finite number in \(0, 10\], got inf"),
        ("motion", "lift", 1.0, "motion.lift is not a setting here: accepted are lift_cm, "),
    ],
)
def test_from_mapping_names_the_bad_value_by_its_place(section, key, value, message):
    values = {key: value} if section is None else {section: {key: value}}
    with pytest.raises(SettingsError, match=message) as err:
        SimSettings.from_mapping(values)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize(
    ("build", "field"),
    [
        (lambda: MotionSettings(lift_cm=-1.0), "lift_cm"),
        (lambda: ControlSettings(settle_s=-1.0), "settle_s"),
        (lambda: IKSettings(method="fast"), "method"),
        (lambda: Camera(distance=0.0), "distance"),
        (lambda: Paper(centre=(0.0, 0.0)), "centre"),
        (lambda: Paper(centre=(0.0, 0.0, 11.0)), "centre[2]"),
        (lambda: SimSettings(scale=float("nan")), "scale"),
        (lambda: SimSettings(camera={"width": 100}), "camera"),
    ],
)
def test_each_dataclass_checks_itself_and_names_the_field_alone(build, field):
    with pytest.raises(SettingsError) as err:
        build()
    assert err.value.field == field and str(err.value).startswith(f"{field} ")


def test_word_centre_is_read_from_the_paper_node_or_the_top_level_not_both():
    assert SimSettings.from_mapping({"paper": {"word_centre_cm": [1, 2]}}).word_centre_cm == (1, 2)
    assert SimSettings.from_mapping({"word_centre_cm": [3, 4]}) == replace(
        SimSettings(), word_centre_cm=(3.0, 4.0)
    )
    with pytest.raises(SettingsError, match="word_centre_cm is given twice"):
        SimSettings.from_mapping({"word_centre_cm": [0, 0], "paper": {"word_centre_cm": [0, 0]}})


def test_from_mapping_keeps_the_defaults_of_what_is_not_given_and_reads_no_other_key():
    settings = SimSettings.from_mapping({"motion": {"lift_cm": 2.0}, "gui": True, "word": None})
    assert settings == replace(SimSettings(), motion=MotionSettings(lift_cm=2.0))
    with pytest.raises(SettingsError, match=r"^ik must be a mapping of settings, got list"):
        SimSettings.from_mapping({"ik": [1, 2]})


def test_the_simulators_nodes_are_declared_by_its_settings_classes():
    for node, cls in NODES.items():
        assert DECLARED[node] == ("prg.sim.settings", cls.__name__)
        declared = declared_ranges(cls, node)
        assert declared and all(RANGES[key] is spec for key, spec in declared.items())
    # written once: TABLE keeps none of their options (paper.word_centre_cm is SimSettings')
    kept = [key for key in TABLE if key.partition(".")[0] in NODES]
    assert kept == ["paper.word_centre_cm"]
    assert "robot.held_joints.*" in RANGES  # a keyed field: one option per joint


def test_the_word_placement_is_declared_with_the_tables_entries():
    assert declared_ranges(SimSettings) == {
        "scale": TABLE["scale"],
        "word_centre_cm": TABLE["paper.word_centre_cm"],
        "tempo": TABLE["tempo"],
        "workspace_step_cm": TABLE["workspace_step_cm"],
    }
    for key, spec in declared_ranges(SimSettings).items():
        assert spec is TABLE["paper.word_centre_cm" if key == "word_centre_cm" else key]


def _outside(spec: Range):
    """One value the range refuses, beside its bounds."""
    if spec.high is not None:
        return spec.high if spec.high_open else spec.high + 1
    return spec.low if spec.low_open else spec.low - 1


def _bad(node: str, field: dataclasses.Field):
    """(the field's bad value in Python, its command-line override, the option named)."""
    spec = field.metadata["range"]
    bad = _outside(spec)
    key = f"{node}.{field.name}"
    if field.metadata["keyed"]:
        joint = next(iter(PANDA["held_joints"]))
        return {**PANDA["held_joints"], joint: bad}, f"{key}.{joint}={bad}", f"{key}.{joint}"
    if field.metadata["items"] is not False:
        default = PANDA[field.name] if node == "robot" else getattr(NODES[node](), field.name)
        value = [bad, *default[1:]]
        return value, f"{key}=[{','.join(map(str, value))}]", f"{key}[0]"
    return bad, f"{key}={bad}", key


def _build(node: str, values: dict):
    if node == "robot":
        return RobotSettings.from_dict(PANDA | values)
    return SimSettings.from_mapping({node: values})


DECLARED_FIELDS = [
    (node, f.name)
    for node, cls in NODES.items()
    for f in dataclasses.fields(cls)
    if "range" in f.metadata
]


@pytest.mark.parametrize(
    ("node", "name"), DECLARED_FIELDS, ids=[".".join(f) for f in DECLARED_FIELDS]
)
def test_each_declared_range_is_refused_in_python_as_the_config_check_refuses_it(node, name):
    field = NODES[node].__dataclass_fields__[name]
    value, _, option = _bad(node, field)
    with pytest.raises(SettingsError) as in_python:
        _build(node, {name: value})
    refused = in_python.value.under("robot") if node == "robot" else in_python.value
    with pytest.raises(UsageError) as in_config:
        check_values({node: {name: value}})
    line = str(in_config.value)
    assert line.startswith(f"{option} must be ")
    # the same line; the config check adds the whole list after a refused item
    assert line.partition(" (in ")[0] == str(refused)


def _simulate(*args: str):
    if (BIN / "prg-simulate").exists():
        return run_cli("prg-simulate", "mlflow=false", "record=false", *args)
    return run_cli("python", "-m", "prg.commands.simulate", "mlflow=false", "record=false", *args)


@pytest.mark.parametrize(
    ("node", "name"), DECLARED_FIELDS, ids=[".".join(f) for f in DECLARED_FIELDS]
)
def test_each_declared_range_is_refused_by_prg_simulate_in_one_line(node, name, tmp_path):
    field = NODES[node].__dataclass_fields__[name]
    value, override, option = _bad(node, field)
    with pytest.raises(SettingsError) as in_python:
        _build(node, {name: value})
    result = _simulate(override, f"paths.root_dir={tmp_path}", f"out_dir={tmp_path / 'out'}")
    assert result.returncode == 2, result.stderr[-2000:]
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"prg-simulate: error: {option} must be ")
    message = str(in_python.value.under("robot") if node == "robot" else in_python.value)
    assert lines[0].removeprefix("prg-simulate: error: ").partition(" (in ")[0] == message
    assert not (tmp_path / "out").exists()


def test_reading_the_settings_imports_neither_numpy_nor_pybullet():
    code = (
        "import sys; from prg.checks import range_of; from prg.sim import SimSettings, "
        "RobotSettings; assert range_of('motion.lift_cm') is not None; "
        "SimSettings.from_mapping({'paper': {'size_cm': [30, 20]}}); RobotSettings.named('panda'); "
        "print(sorted({'numpy', 'pybullet'} & set(sys.modules)))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
