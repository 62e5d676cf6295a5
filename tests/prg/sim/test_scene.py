"""Scene.render_view: a TinyRenderer picture of the scene from any viewpoint (the README figure)."""

from __future__ import annotations

import numpy as np

from prg.sim import RobotSettings, Scene, SimSettings

EYE, TARGET = (-0.4, 1.0, 1.45), (0.42, 0.02, 0.85)  # docs/make_figures.py's 3/4 view


def test_a_three_quarter_view_shows_the_arm_over_the_lit_page():
    robot, settings = RobotSettings.named("panda"), SimSettings()  # conf/simulate.yaml's
    with Scene(robot, settings.paper) as scene:
        view = scene.render_view(EYE, TARGET, size=(240, 160))
        assert np.array_equal(view, scene.render_view(EYE, TARGET, size=(240, 160)))
        centre = settings.paper.centre
        top = scene.render_view((centre[0], centre[1], 1.2), centre, (240, 160), up=(1, 0, 0))
        # the same scene without the arm: its base (and the pen with it) moved out of sight
        scene.p.resetBasePositionAndOrientation(
            scene.robot.body, (0, 0, -10), (0, 0, 0, 1), physicsClientId=scene.cid
        )
        empty = scene.render_view(EYE, TARGET, size=(240, 160))
    assert view.shape == (160, 240, 3) and view.dtype == np.uint8
    assert len(np.unique(view.reshape(-1, 3), axis=0)) > 500  # a lit scene, not a blank image
    arm = np.abs(view.astype(int) - empty.astype(int)).max(axis=2) > 30
    assert 0.05 < arm.mean() < 0.6  # the arm covers part of the picture, not all of it
    assert np.all(top[80, 120] > 200)  # straight down at the paper's centre: the white paper,
    assert top[5, 5, 2] < 200  # the wooden table at the corner
