"""Tests of ``prg.tracking.task_runs`` (moved from the suite on: one MLflow run per command's work
(``prg.tracking.task_run``), on a real SQLite store: its params, metrics and artifacts, and its
status when the work completes, fails or is stopped; logged in the command's process or handed
to a background logger (``background=True``))."""

from __future__ import annotations

import pytest
from omegaconf import OmegaConf

from prg.signals import Interrupted
from prg.tracking import PendingRun, TaskRun, log_pending_run, mlflow_client, sqlite_uri, task_run
from tests.conftest import wait_for_pending_runs


@pytest.fixture()
def cfg(tmp_path):
    return OmegaConf.create(
        {
            "run_name": "task-run-test",
            "paths": {"root_dir": str(tmp_path), "log_dir": str(tmp_path / "logs")},
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


@pytest.mark.parametrize("background", [False, True])
def test_a_completed_task_is_finished_with_its_params_metrics_and_artifacts(
    cfg, tmp_path, background
):
    folder = tmp_path / "out"
    folder.mkdir()
    (folder / "word.json").write_text("{}")
    with task_run(cfg, "write", {"prg.family": "muse"}, background=background) as run:
        assert isinstance(run, PendingRun if background else TaskRun)
        assert (tmp_path / "mlruns.db").exists() != background  # handed off: no store opened
        run.log_params({"text": "cat", "generate": {"speed_cm_s": 2.0, "seed": 0}})
        run.log_metrics({"latency_ms": 12.5, "points": 7, "not_a_number": "x"}, prefix="write/")
        run.set_tag("prg.text", "cat")
        run.log_text("a note", "note.txt")
        run.log_artifacts(folder, "word")
    wait_for_pending_runs(tmp_path)
    (found,) = _runs(cfg)
    assert found.data.tags["prg.text"] == "cat"
    assert found.info.end_time >= found.info.start_time
    assert found.info.status == "FINISHED" and found.info.run_name == "task-run-test"
    assert found.data.tags["prg.task"] == "write" and found.data.tags["prg.family"] == "muse"
    assert found.data.tags["mlflow.note.content"].startswith("**prg-write**: a word written")
    assert client_experiments(cfg) == ["prg-tests-tasks"]  # no training experiment is made
    assert found.data.params == {"text": "cat", "generate.speed_cm_s": "2.0", "generate.seed": "0"}
    assert found.data.metrics == {"write/latency_ms": 12.5, "write/points": 7.0}
    client = mlflow_client(cfg.logger.tracking_uri)
    assert [a.path for a in client.list_artifacts(found.info.run_id, "word")] == ["word/word.json"]
    assert client.download_artifacts(found.info.run_id, "note.txt", str(tmp_path))


def client_experiments(cfg) -> list[str]:
    client = mlflow_client(cfg.logger.tracking_uri)
    return [e.name for e in client.search_experiments() if e.name != "Default"]


@pytest.mark.parametrize(
    ("error", "status"),
    [(ValueError("the work failed"), "FAILED"), (Interrupted(15), "KILLED")],
)
@pytest.mark.parametrize("background", [False, True])
def test_a_failed_or_stopped_task_is_marked_so_and_the_error_goes_on(
    cfg, tmp_path, error, status, background
):
    with pytest.raises(type(error)), task_run(cfg, "evaluate", background=background):
        raise error
    wait_for_pending_runs(tmp_path)
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


def test_a_pending_run_that_cannot_be_logged_is_kept_whole_for_a_retry(cfg, tmp_path):
    import time

    folder = tmp_path / "out"
    folder.mkdir()
    (folder / "word.json").write_text("{}")
    (folder / "word.png").symlink_to(tmp_path / "deleted.png")  # unreadable when logged
    with task_run(cfg, "write", background=True) as run:
        run.log_metrics({"points": 3})
        run.log_artifacts(folder, "word")
    pending = tmp_path / "logs" / "pending-runs"
    log = pending / "log.txt"
    deadline = time.monotonic() + 120
    while "not logged" not in (log.read_text() if log.exists() else ""):
        assert time.monotonic() < deadline, "the background logger never gave up"
        time.sleep(0.1)
    (line,) = [x for x in log.read_text().splitlines() if x.startswith("prg.tracking: error")]
    (path,) = pending.glob("*.json")
    assert f"pending run {path} not logged" in line and "log-pending" in line
    assert _runs(cfg) == []  # the half-logged run is deleted
    folder.rename(tmp_path / "moved")
    with pytest.raises(FileNotFoundError, match=r"output folder .* is gone"):
        log_pending_run(path)  # refused before a run is made
    assert path.is_file() and _runs(cfg) == []
    (tmp_path / "moved").rename(folder)
    (folder / "word.png").unlink()
    run_id = log_pending_run(path)
    assert not path.exists()
    (found,) = _runs(cfg)
    assert found.info.run_id == run_id and found.data.metrics == {"points": 3.0}
