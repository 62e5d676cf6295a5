"""Tests of ``prg.commands.cli`` (moved from the suite on: a written word exported to real machines
(prg.export, prg-export): every file is read back with another reader (gcodeparser, an HPGL
parser written here, vpype's SVG reader, mcap-ros2's reader, numpy) and compared with what the
word, its DMP timing and the simulated arm say independently; the joint-limit check slows a too-
fast timing by the smallest factor and refuses what no slow-down fixes)."""

from __future__ import annotations

import pytest

from prg.commands.cli import compose_config

# ----------------------------------------------------------------------------- the command


def test_the_simulation_settings_of_prg_export_are_prg_simulates():
    export, simulate = compose_config("export", []), compose_config("simulate", [])
    for key in ("paper", "motion", "control", "ik", "workspace_step_cm", "scale", "tempo"):
        assert export[key] == simulate[key], key
    assert export.robot == simulate.robot


PAPER_BATCH = {"cvae": 128, "avae_ts": 128, "avae_ti": 128, "muse": 64}


@pytest.mark.parametrize("family", list(PAPER_BATCH))
def test_paper_profile_keeps_the_papers_hyper_parameters(family, tmp_path):
    cfg = compose_config("train", [f"model={family}", "experiment=paper"])
    module = cfg.model.module
    assert cfg.model.batch_size == PAPER_BATCH[family]
    assert module.optimizer._target_ == "torch.optim.Adam" and module.optimizer.lr == 1e-4
    assert module.scheduler is None and not module.zero_init_trajectory
    assert module.get("kl_warmup_epochs", 0) == 0 and module.image_shift == 0
    assert cfg.trainer.precision == "32-true" and cfg.trainer.max_epochs == 50


@pytest.mark.parametrize("profile", ["quick", "converged"])
@pytest.mark.parametrize("family", list(PAPER_BATCH))
def test_fast_profiles_share_one_recipe(profile, family):
    cfg = compose_config("train", [f"model={family}", f"experiment={profile}"])
    module = cfg.model.module
    assert cfg.profile == profile
    assert module.scheduler._target_ == "torch.optim.lr_scheduler.OneCycleLR"
    assert module.scheduler.max_lr == module.optimizer.lr
    assert module.zero_init_trajectory and cfg.trainer.precision == "bf16-mixed"
    assert module.image_shift == 2
    assert isinstance(cfg.trainer.max_epochs, int) and cfg.trainer.max_epochs >= 1
    assert cfg.trainer.accelerator == "auto"
