"""Tests of ``prg.tracking.sweep``: the parent run of a multirun, and of the same sweep run again."""

import pytest

from prg.commands.cli import compose_config
from prg.tracking import PARENT_ENV, SweepParentRun, mlflow_client, sqlite_uri


def _sweep(tmp_path, *overrides: str) -> str:
    """Open and close a sweep's parent run as Hydra does; its id."""
    config = compose_config("train", [f"paths.root_dir={tmp_path}", *overrides], True)
    callback = SweepParentRun()
    callback.on_multirun_start(config)
    run_id = callback.run_id
    callback.on_multirun_end(config)
    return run_id


@pytest.fixture(autouse=True)
def _no_parent(monkeypatch):
    monkeypatch.delenv(PARENT_ENV, raising=False)


def test_the_same_sweep_again_continues_its_parent_run(tmp_path):
    first = _sweep(tmp_path, "model=cvae", "seed=1")
    client = mlflow_client(sqlite_uri(tmp_path / "mlruns.db"))
    assert client.get_run(first).info.status == "FINISHED"
    assert _sweep(tmp_path, "seed=1", "model=cvae") == first  # overrides in any order
    assert client.get_run(first).info.status == "FINISHED"
    others = {
        _sweep(tmp_path, "model=cvae", "seed=2"),  # another sweep
        _sweep(tmp_path, "model=cvae", "seed=1", "resume=never"),  # its jobs all run again
    }
    assert first not in others and len(others) == 2
    experiment = client.get_experiment_by_name("prg").experiment_id
    assert len(client.search_runs([experiment])) == 3
