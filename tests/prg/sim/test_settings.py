"""The simulator's settings: library defaults are the config's, named robots, one typed boundary
(:meth:`SimSettings.from_mapping`) whose errors name the field and its place (no PyBullet)."""

from __future__ import annotations

from dataclasses import replace

import pytest

from prg.errors import SettingsError
from prg.sim import (
    Camera,
    ControlSettings,
    IKSettings,
    MotionSettings,
    Paper,
    SimSettings,
)
from tests.helpers.sim_settings import CONF, _yaml


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
        ("motion", "lift_cm", 0, "motion.lift_cm must be a positive number, got 0"),
        ("motion", "dwell_s", -1.0, "motion.dwell_s must be >= 0, got -1.0"),
        ("control", "time_step", -0.01, r"control.time_step must be in \(0, 0.05\] s"),
        ("control", "steps_per_waypoint", 2.5, "control.steps_per_waypoint must be a positive"),
        ("control", "position_gain", "x", "control.position_gain must be a number, got 'x'"),
        ("ik", "method", "fast", "ik.method 'fast': choose refined, null_space, plain"),
        ("ik", "cold_iterations", True, "ik.cold_iterations must be a number, got True"),
        ("camera", "width", 0, r"camera.width must be a whole number of pixels in \[16, 8192\]"),
        ("camera", "fov", 200.0, r"camera.fov must be in \[1, 170\] degrees"),
        ("paper", "size_cm", [0, 29.7], r"paper.size_cm must be two positive numbers, got \(0, "),
        ("paper", "thickness_m", 0, "paper.thickness_m must be positive, got 0.0"),
        ("paper", "word_centre_cm", [1.0], r"paper.word_centre_cm must be two numbers"),
        (None, "word_centre_cm", [1.0], r"^word_centre_cm must be two numbers"),
        (None, "scale", 0, "^scale must be a positive number, got 0.0"),
        (None, "tempo", float("inf"), "^tempo must be a positive number, got inf"),
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
