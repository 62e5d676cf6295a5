"""One MLflow run per command's work (``prg.tracking.task_run``), on a real SQLite store: its
params, metrics and artifacts, and its status when the work completes, fails or is stopped;
logged in the command's process or handed to a background logger (``background=True``)."""

from __future__ import annotations

import pytest

from prg.errors import UsageError
from prg.tracking import log_pending_run, mlflow_client, sqlite_uri


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
        "mlflow_background=false",  # logged before the command returns
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


def test_a_file_that_is_not_a_pending_run_gets_one_line(tmp_path):
    import subprocess
    import sys

    bad = tmp_path / "bad.json"
    bad.write_text('{"tracking_uri": "sqlite:///x.db"}')
    with pytest.raises(UsageError, match="not a pending run file"):
        log_pending_run(bad)
    result = subprocess.run(
        [sys.executable, "-m", "prg.tracking", "log-pending", str(bad)],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 2 and len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert f"pending run {bad}: not a pending run file" in result.stderr
    assert bad.is_file()
