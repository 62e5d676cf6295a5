"""One MLflow run per command's work (``prg.tracking.task_run``), on a real SQLite store: its
params, metrics and artifacts, and its status when the work completes, fails or is stopped."""

from __future__ import annotations

import pytest
from omegaconf import OmegaConf

from prg.signals import Interrupted
from prg.tracking import mlflow_client, sqlite_uri, task_run


@pytest.fixture()
def cfg(tmp_path):
    return OmegaConf.create(
        {
            "run_name": "task-run-test",
            "paths": {"root_dir": str(tmp_path)},
            "logger": {
                "experiment_name": "prg-tests",
                "task_experiment_name": "prg-tests-tasks",
                "tracking_uri": sqlite_uri(tmp_path / "mlruns.db"),
                "artifact_location": str(tmp_path / "mlartifacts"),
            },
        }
    )


def _runs(cfg):
    client = mlflow_client(cfg.logger.tracking_uri)
    experiment = client.get_experiment_by_name(cfg.logger.task_experiment_name)
    return client.search_runs([experiment.experiment_id])


def test_a_completed_task_is_finished_with_its_params_metrics_and_artifacts(cfg, tmp_path):
    folder = tmp_path / "out"
    folder.mkdir()
    (folder / "word.json").write_text("{}")
    with task_run(cfg, "write", {"prg.family": "muse"}) as run:
        run.log_params({"text": "cat", "generate": {"speed_cm_s": 2.0, "seed": 0}})
        run.log_metrics({"latency_ms": 12.5, "points": 7, "not_a_number": "x"}, prefix="write/")
        run.log_artifacts(folder, "word")
    (found,) = _runs(cfg)
    assert found.info.status == "FINISHED" and found.info.run_name == "task-run-test"
    assert found.data.tags["prg.task"] == "write" and found.data.tags["prg.family"] == "muse"
    assert found.data.tags["mlflow.note.content"].startswith("**prg-write**: a word written")
    assert client_experiments(cfg) == ["prg-tests-tasks"]  # no training experiment is made
    assert found.data.params == {"text": "cat", "generate.speed_cm_s": "2.0", "generate.seed": "0"}
    assert found.data.metrics == {"write/latency_ms": 12.5, "write/points": 7.0}
    client = mlflow_client(cfg.logger.tracking_uri)
    assert [a.path for a in client.list_artifacts(found.info.run_id, "word")] == ["word/word.json"]


def client_experiments(cfg) -> list[str]:
    client = mlflow_client(cfg.logger.tracking_uri)
    return [e.name for e in client.search_experiments() if e.name != "Default"]


@pytest.mark.parametrize(
    ("error", "status"),
    [(ValueError("the work failed"), "FAILED"), (Interrupted(15), "KILLED")],
)
def test_a_failed_or_stopped_task_is_marked_so_and_the_error_goes_on(cfg, error, status):
    with pytest.raises(type(error)), task_run(cfg, "evaluate"):
        raise error
    (found,) = _runs(cfg)
    assert found.info.status == status


def test_disabled_opens_nothing(cfg, tmp_path):
    with task_run(cfg, "write", enabled=False) as run:
        assert run is None
    assert not (tmp_path / "mlruns.db").exists()


def test_inside_a_sweep_the_run_is_a_child_of_the_parent(cfg, monkeypatch):
    monkeypatch.setenv("PRG_PARENT_RUN_ID", "0123456789abcdef")
    with task_run(cfg, "simulate"):
        pass
    (found,) = _runs(cfg)
    assert found.data.tags["mlflow.parentRunId"] == "0123456789abcdef"


def test_a_command_whose_work_fails_leaves_a_failed_run(tmp_path, untrained_muse_checkpoint):
    import json

    from tests.conftest import run_cli

    strokes = tmp_path / "two.json"
    strokes.write_text(json.dumps([[[0, 0], [1, 1]], [[0, 1], [1, 0]]]))
    result = run_cli(
        "prg-write",
        "text=cat",
        f"trajectories={strokes}",
        f"ckpt={untrained_muse_checkpoint}",
        f"paths.root_dir={tmp_path}",
        f"out_dir={tmp_path / 'out'}",
    )
    assert result.returncode == 2, result.stderr[-2000:]
    assert "trajectories= gives 2 letters" in result.stderr
    client = mlflow_client(sqlite_uri(tmp_path / "mlruns.db"))
    (found,) = client.search_runs([e.experiment_id for e in client.search_experiments()])
    assert found.info.status == "FAILED" and found.data.tags["prg.task"] == "write"
    assert client.get_experiment(found.info.experiment_id).name == "prg-tasks"
    note = found.data.tags["mlflow.note.content"]  # the command line as typed
    assert "Command: `prg-write text=cat trajectories=" in note and "Model: `muse`" in note
    assert not (tmp_path / "out").exists()
