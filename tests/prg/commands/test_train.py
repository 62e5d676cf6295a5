"""Tests of ``prg.commands.train`` (moved from the suite on: `prg-train`: MLflow records,
checkpoints, resume, sweeps, bad input — real SQLite stores)."""

import pytest
import torch

from prg.commands.cli import compose_config
from prg.commands.train import train
from tests.helpers.train import FAST, _cfg, _client


def test_run_records_params_metrics_config_figures_and_checkpoint(tmp_path, small_dataset):
    result = train(_cfg(tmp_path, small_dataset, "model=avae_ts"))
    client = _client(tmp_path)
    run = client.get_run(result.run_id)
    assert run.data.params["model.name"] == "avae_ts"
    assert run.data.params["model.module.optimizer.lr"] == "0.0001"
    assert run.data.tags["prg.family"] == "avae_ts"
    assert run.data.tags["prg.data.source"] == "synthetic"
    assert len(run.data.tags["prg.data.manifest_sha256"]) == 64
    assert run.data.tags["prg.git_commit"]
    history = client.get_metric_history(result.run_id, "train/loss")
    assert [m.step for m in history] == sorted(m.step for m in history) and len(history) == 2
    for name in ("val/loss", "train/rec_T", "train/kl_S", "train/skl", "val/nll_per_dim_T"):
        assert name in run.data.metrics
    artifacts = {a.path for a in client.list_artifacts(result.run_id, "figures/final")}
    assert {"figures/final/label_to_traj.png", "figures/final/recon_traj.png"} <= artifacts
    assert [a.path for a in client.list_artifacts(result.run_id, "config")] == [
        "config/config.yaml"
    ]
    assert [a.path for a in client.list_artifacts(result.run_id, "checkpoints")] == [
        "checkpoints/best.ckpt"
    ]
    ckpt_dir = tmp_path / "checkpoints/prg/avae_ts-seed0"
    outputs = {p.name for p in ckpt_dir.iterdir() if not p.name.startswith(".")}
    assert outputs == {"best.ckpt", "last.ckpt", "finished.json"}  # finished.json: resume=auto


def test_resume_from_last_checkpoint_continues_the_same_run(tmp_path, small_dataset):
    every = "trainer.log_every_n_steps=2"  # 3 batches an epoch: a window spans the resume
    first = train(_cfg(tmp_path, small_dataset, "model=cvae", "trainer.max_epochs=1", every))
    last = tmp_path / "checkpoints/prg/cvae-seed0/last.ckpt"
    saved = torch.load(last, weights_only=False)
    assert saved["mlflow_run_id"] == first.run_id
    earlier = saved["callbacks"]["FitTime"]  # the fit's time up to that checkpoint
    assert first.metrics["fit_starts"] == 1 and earlier["starts"] == 1
    assert 0 < earlier["wall_s"] <= first.metrics["fit_wall_s"]
    second = train(
        _cfg(
            tmp_path,
            small_dataset,
            "model=cvae",
            "trainer.max_epochs=2",
            f"ckpt_path={last}",
            every,
        )
    )
    assert second.run_id == first.run_id
    # its time: the earlier start's up to the checkpoint, and its own
    assert second.metrics["fit_starts"] == 2
    assert second.metrics["fit_wall_s"] > earlier["wall_s"]
    assert second.metrics["fit_cpu_s"] > earlier["cpu_s"]
    client = _client(tmp_path)
    assert len(client.search_runs([client.get_experiment_by_name("prg").experiment_id])) == 1
    epochs = [m.value for m in client.get_metric_history(first.run_id, "epoch")]
    assert sorted(set(epochs)) == [0.0, 1.0]
    epoch_means = client.get_metric_history(first.run_id, "train/loss")
    assert len(epoch_means) == 2
    # steps 1-2, 3-4 (across the resume: its first step came back from the checkpoint), 5-6
    windows = client.get_metric_history(first.run_id, "train_steps/loss")
    assert [m.step for m in windows] == [1, 3, 5]
    assert 2 * sum(m.value for m in windows) == pytest.approx(
        3 * sum(m.value for m in epoch_means), rel=1e-5
    )


def test_same_seed_same_losses_and_the_same_exported_file(tmp_path, small_dataset):
    from prg.models.checkpoint import RUN_FACTS, load_model

    def run(name):  # another project root: another MLflow store, run id and checkpoint folder
        root = tmp_path / name
        args = ("model=cvae", "trainer.max_epochs=1", f"export_dir={root}/export")
        return train(_cfg(root, small_dataset, *args)), root / "export" / "model.ckpt"

    (a, a_file), (b, b_file) = run("a"), run("b")
    assert a.metrics["train/loss"] == b.metrics["train/loss"]
    assert a.metrics["val/loss"] == b.metrics["val/loss"]
    assert a.run_id != b.run_id
    assert a_file.read_bytes() == b_file.read_bytes()  # no run facts inside
    assert not set(RUN_FACTS) & set(torch.load(a_file, weights_only=True))
    assert load_model(a_file)[1]["mlflow_run_id"] == a.run_id  # from metrics.json beside it


def test_paper_profile_registers_the_best_checkpoint(tmp_path, small_dataset):
    result = train(_cfg(tmp_path, small_dataset, "model=cvae", "experiment=paper", *FAST))
    client = _client(tmp_path)
    versions = client.search_model_versions("name='prg-cvae'")
    assert len(versions) == 1 and versions[0].run_id == result.run_id
    run = client.get_run(result.run_id)
    assert versions[0].source == run.data.tags["prg.model_uri"]  # the servable MLflow model
    assert float(versions[0].tags["metric.val_loss"]) == pytest.approx(
        run.data.metrics["val/loss"], rel=1e-5
    )
    assert client.get_model_version_by_alias("prg-cvae", "champion").version == versions[0].version
    assert client.get_run(result.run_id).data.tags["prg.experiment"] == "paper"


def test_quick_profile_trains_with_the_recipe_on_the_cpu(tmp_path, small_dataset):
    result = train(_cfg(tmp_path, small_dataset, "model=muse", "experiment=quick", *FAST))
    assert result.trainer.state.finished and result.trainer.current_epoch == 2
    assert result.trainer.precision == "bf16-mixed"
    scheduler = result.trainer.lr_scheduler_configs[0].scheduler
    assert type(scheduler).__name__ == "OneCycleLR" and scheduler.total_steps == 6
    assert result.module.model.kl_scale == 1.0  # a 1-epoch warm-up is over after 2 epochs
    run = _client(tmp_path).get_run(result.run_id)
    assert run.data.tags["prg.experiment"] == "quick" and run.info.status == "FINISHED"


def test_converged_profile_stops_when_validation_stops_improving(tmp_path, small_dataset):
    # an improvement threshold no run can meet: early stopping, watching from the second half
    # of the run (epoch index 3 of 6), ends it `patience` epochs later
    result = train(
        _cfg(
            tmp_path,
            small_dataset,
            "model=cvae",
            "experiment=converged",
            *FAST,
            "trainer.max_epochs=6",
            "callbacks.early_stopping.patience=1",
            "callbacks.early_stopping.min_delta=1e9",
        )
    )
    assert result.trainer.should_stop and result.trainer.current_epoch == 5  # 6 allowed
    assert _client(tmp_path).get_run(result.run_id).info.status == "FINISHED"


def test_resuming_a_one_cycle_run_with_a_larger_budget_is_refused(tmp_path, small_dataset):
    from prg.errors import UsageError

    train(_cfg(tmp_path, small_dataset, "model=cvae", "experiment=quick", *FAST))
    longer = _cfg(
        tmp_path, small_dataset, "model=cvae", "experiment=quick", *FAST, "ckpt_path=last"
    )
    longer.trainer.max_epochs = 4
    with pytest.raises(UsageError, match="schedule spans 6 steps, the resumed run asks for 12"):
        train(longer)


def test_the_datamodule_is_built_from_its_config_node_with_todays_overrides(small_dataset):
    from prg.commands.train import build_datamodule, train_settings
    from prg.data.datamodule import PRGDataModule

    cfg = compose_config(
        "train",
        [
            f"paths.data_dir={small_dataset}",
            "model=avae_ti",
            "model.batch_size=7",
            "data.loader.num_workers=0",
            "seed=3",
        ],
    )
    assert cfg.datamodule._target_ == "prg.data.datamodule.PRGDataModule"
    datamodule = build_datamodule(cfg)
    assert isinstance(datamodule, PRGDataModule)
    assert datamodule.root == small_dataset / "prepared/synthetic"
    assert datamodule.modalities == ("traj", "image")
    assert (datamodule.batch_size, datamodule.num_workers, datamodule.seed) == (7, 0, 3)
    assert train_settings(cfg).modalities == ("traj", "image")


def test_a_model_whose_modalities_the_data_lack_is_refused_in_one_line():
    from prg.commands.train import train_settings
    from prg.errors import UsageError

    cfg = compose_config("train", ["model=avae_ti", "data.loader.modalities=[traj,label]"])
    with pytest.raises(UsageError) as err:
        train_settings(cfg)
    assert str(err.value) == (
        "model avae_ti needs modalities ['traj', 'image'] but the data provides ['traj', "
        "'label'] (data.loader.modalities): ['image'] missing"
    )


def test_the_run_logs_its_dataset_with_the_manifests_digest(tmp_path, small_dataset):
    import hashlib

    result = train(_cfg(tmp_path, small_dataset, "model=cvae", "trainer.max_epochs=1"))
    run = _client(tmp_path).get_run(result.run_id)
    (used,) = run.inputs.dataset_inputs
    manifest = small_dataset / "prepared" / "synthetic" / "manifest.json"
    sha = hashlib.sha256(manifest.read_bytes()).hexdigest()
    assert used.dataset.name == "synthetic" and used.dataset.digest == sha[:36]
    assert run.data.tags["prg.data.manifest_sha256"] == sha
    assert str(manifest.parent.resolve()) in used.dataset.source
    assert [(t.key, t.value) for t in used.tags] == [("mlflow.data.context", "training")]


def _plan_cfg(tmp_path, *overrides: str):
    return compose_config(
        "train", [f"paths.root_dir={tmp_path}", "model=muse", "resume=auto", *overrides]
    )


def test_resume_auto_skips_only_a_job_finished_with_the_same_identity(tmp_path):
    import json

    from prg.commands.train import FINISHED, job_identity, plan_job

    cfg = _plan_cfg(tmp_path)
    identity = job_identity(cfg, "a" * 64)
    assert plan_job(cfg, identity).action == "fresh"  # nothing there
    folder = tmp_path / "checkpoints/prg/muse-seed0"
    folder.mkdir(parents=True)
    (folder / FINISHED).write_text(json.dumps({"identity": identity, "mlflow_run_id": "r1"}))
    plan = plan_job(cfg, identity)
    assert (plan.action, plan.finished["mlflow_run_id"]) == ("skip", "r1")
    # how to run a job is not which job: resume and ckpt_path leave the identity as it is
    assert job_identity(_plan_cfg(tmp_path, "resume=never"), "a" * 64) == identity
    # another config, data or seed: never skipped
    for other in (
        job_identity(_plan_cfg(tmp_path, "trainer.max_epochs=3"), "a" * 64),
        job_identity(cfg, "b" * 64),
    ):
        plan = plan_job(cfg, other)
        assert plan.action == "fresh" and "another config" in plan.reason
    # finished, but its export is gone (DVC removes a stage's outputs): trained again
    exported = _plan_cfg(tmp_path, f"export_dir={tmp_path / 'models/muse'}")
    identity = job_identity(exported, "a" * 64)
    (folder / FINISHED).write_text(json.dumps({"identity": identity}))
    plan = plan_job(exported, identity)
    assert plan.action == "fresh" and "export" in plan.reason


def test_resume_auto_resumes_only_a_last_checkpoint_of_the_same_identity(
    tmp_path, untrained_muse_checkpoint
):
    from prg.commands.train import IDENTITY_KEY, job_identity, plan_job

    cfg = _plan_cfg(tmp_path)
    identity = job_identity(cfg, "a" * 64)
    last = tmp_path / "checkpoints/prg/muse-seed0/last.ckpt"
    last.parent.mkdir(parents=True)
    ckpt = torch.load(untrained_muse_checkpoint, weights_only=False)
    torch.save({**ckpt, "global_step": 7, IDENTITY_KEY: identity}, last)
    plan = plan_job(cfg, identity)
    assert (plan.action, plan.ckpt_path, plan.checkpoint["global_step"]) == ("resume", str(last), 7)
    other = job_identity(_plan_cfg(tmp_path, "seed=0", "model.batch_size=8"), "a" * 64)
    assert plan_job(cfg, other).action == "fresh"  # a checkpoint of another config
    torch.save(ckpt, last)  # one written before checkpoints carried their identity
    assert plan_job(cfg, identity).action == "fresh"
    last.write_text("not a checkpoint")
    assert plan_job(cfg, identity).action == "fresh"


def test_resume_mode_sweep_is_auto_in_multiruns_only_and_bad_values_are_refused():
    from prg.checks import check_values
    from prg.commands.train import resume_mode
    from prg.errors import UsageError

    assert resume_mode(compose_config("train", [])) == "never"  # a single run, no HydraConfig
    assert resume_mode(compose_config("train", ["resume=auto"])) == "auto"
    with pytest.raises(UsageError, match="unknown resume mode always; accepted: sweep, auto"):
        check_values(compose_config("train", ["resume=always"]))
