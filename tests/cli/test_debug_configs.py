"""`prg-train debug=fdr|overfit|limit|profiler` (conf/debug/): each composes and runs on the small
dataset, through the real trainer and a real MLflow SQLite store."""

from pathlib import Path

import pytest
from mlflow import MlflowClient

from prg.commands.cli import compose_config
from prg.commands.train import train
from prg.tracking import sqlite_uri
from tests.conftest import run_cli


def _train(tmp_path: Path, data_dir: Path, *overrides: str):
    cfg = compose_config(
        "train",
        [
            f"paths.root_dir={tmp_path}",
            f"paths.data_dir={data_dir}",
            "trainer.enable_progress_bar=false",
            *overrides,
        ],
    )
    return cfg, train(cfg)


def _runs(root: Path) -> list:
    client = MlflowClient(sqlite_uri(root / "mlruns.db"))
    return [r for e in client.search_experiments() for r in client.search_runs([e.experiment_id])]


@pytest.mark.parametrize("debug", ["fdr", "overfit", "limit", "profiler"])
def test_every_debug_config_composes_on_top_of_a_profile(debug):
    cfg = compose_config("train", ["model=muse", "experiment=quick", f"debug={debug}"])
    assert cfg.trainer.accelerator == "cpu" and cfg.trainer.detect_anomaly is True
    assert cfg.data.loader.num_workers == 0 and cfg.profile == "debug"
    assert cfg.export_dir is None and "debug" in cfg.checkpoint_dir


def test_fdr_runs_one_batch_and_leaves_no_run_and_no_checkpoint(tmp_path, small_dataset):
    cfg, result = _train(tmp_path, small_dataset, "model=cvae", "debug=fdr")
    assert result.trainer.global_step == 1 and result.run_id is None
    assert not Path(cfg.checkpoint_dir).exists() or not any(Path(cfg.checkpoint_dir).iterdir())
    assert not (tmp_path / "mlruns.db").exists() or _runs(tmp_path) == []


def test_overfit_drives_the_loss_of_three_batches_far_down(tmp_path, small_dataset):
    _, result = _train(tmp_path, small_dataset, "model=cvae", "experiment=quick", "debug=overfit")
    client = MlflowClient(sqlite_uri(tmp_path / "mlruns.db"))
    history = [m.value for m in client.get_metric_history(result.run_id, "train/loss")]
    assert result.trainer.current_epoch == 20 and len(history) >= 10
    assert history[-1] < history[0] - 0.5 * abs(history[0])  # falls by half its size at least
    run = client.get_run(result.run_id)
    assert run.data.tags["prg.experiment"] == "debug" and run.info.status == "FINISHED"


def test_limit_runs_the_whole_loop_on_a_few_batches(tmp_path, small_dataset):
    cfg, result = _train(tmp_path, small_dataset, "model=avae_ts", "debug=limit")
    assert result.trainer.current_epoch == 3 and result.trainer.global_step == 15
    assert Path(result.last_checkpoint).is_file() and Path(result.best_checkpoint).is_file()
    assert Path(cfg.checkpoint_dir) == Path(result.last_checkpoint).parent


def test_profiler_writes_its_report_from_the_command_line(tmp_path, small_dataset):
    result = run_cli(
        "prg-train",
        "model=cvae",
        "debug=profiler",
        f"paths.root_dir={tmp_path}",
        f"paths.data_dir={small_dataset}",
        "trainer.enable_progress_bar=false",
        "trainer.limit_train_batches=5",
        cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    (report,) = (tmp_path / "logs" / "profiler").glob("*profiler-debug-cvae-seed0.txt")
    text = report.read_text()
    assert "run_training_batch" in text and "Total" in text


def test_training_runs_log_system_metrics_by_default(tmp_path, small_dataset):
    """MLflow's system-metrics monitor on the training run (conf/callbacks: system_metrics)."""
    _, result = _train(
        tmp_path,
        small_dataset,
        "model=cvae",
        "trainer.max_epochs=15",  # a few seconds: several samples of the monitor
        "callbacks.figures=null",
        "callbacks.system_metrics.sampling_interval_s=0.2",
    )
    client = MlflowClient(sqlite_uri(tmp_path / "mlruns.db"))
    metrics = client.get_run(result.run_id).data.metrics
    assert {"system/cpu_utilization_percentage", "system/system_memory_usage_megabytes"} <= set(
        metrics
    ), sorted(metrics)
    assert metrics["system/system_memory_usage_megabytes"] > 0


def test_system_metrics_can_be_turned_off(tmp_path, small_dataset):
    _, result = _train(
        tmp_path, small_dataset, "model=cvae", "debug=limit", "callbacks.system_metrics=null"
    )
    metrics = MlflowClient(sqlite_uri(tmp_path / "mlruns.db")).get_run(result.run_id).data.metrics
    assert not [k for k in metrics if k.startswith("system/")]
