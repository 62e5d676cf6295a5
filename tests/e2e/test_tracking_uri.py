"""Nothing lands in MLflow's own default store: with no tracking URI set, MLflow 3 opens
``sqlite:///mlflow.db`` in the working folder. Registering a model (``python -m
prg.commands.serving register``, :func:`prg.serving.register_version`) sets MLflow's global URI for
the registry and must leave it unset again, not pointing at that default: MLflow exports the
global URI as ``MLFLOW_TRACKING_URI``, which the project's :func:`prg.tracking.tracking_uri` puts
first, so every later run of the process (and of its children) would go to ``./mlflow.db``.

Each case runs in a fresh process (MLflow's global URI is per process, and this test process's
may have been set by other tests) whose working folder is a temporary one, away from the store."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

REGISTER_THEN_RUN = textwrap.dedent(
    """
    import json, os, sys
    from pathlib import Path

    from omegaconf import OmegaConf

    from prg.commands.serving import main
    from prg.tracking import get_experiment_id, mlflow_client, sqlite_uri, task_run

    root = Path(sys.argv[1])
    store = sqlite_uri(root / "mlruns.db")
    client = mlflow_client(store)
    experiment = get_experiment_id(client, "prg", (root / "mlartifacts").as_uri())
    run_id = client.create_run(experiment, run_name="trained").info.run_id
    model = client.create_logged_model(experiment, name="model", source_run_id=run_id)
    client.set_tag(run_id, "prg.model_uri", f"models:/{model.model_id}")
    export = root / "models" / "muse"
    export.mkdir(parents=True)
    exported = {"family": "muse", "mlflow_run_id": run_id, "val_loss": 1.0}
    (export / "metrics.json").write_text(json.dumps(exported))
    assert main(["register", str(export), "--tracking-uri", store]) == 0

    # the same process then runs a command's work on the configured (default) store
    cfg = OmegaConf.create(
        {
            "run_name": "after-register",
            "paths": {"root_dir": str(root), "log_dir": str(root / "logs")},
            "logger": {
                "tracking_uri": None,
                "experiment_name": "prg",
                "task_experiment_name": "prg-tasks",
                "artifact_location": str(root / "mlartifacts"),
            },
        }
    )
    with task_run(cfg, "write") as run:
        pass
    print(json.dumps({"env": os.environ.get("MLFLOW_TRACKING_URI"), "store": run.client.tracking_uri}))
    """
)


def _clean_env() -> dict[str, str]:
    """This environment without a tracking URI, a registry URI or a project root."""
    return {
        k: v
        for k, v in os.environ.items()
        if k not in ("MLFLOW_TRACKING_URI", "MLFLOW_REGISTRY_URI", "PRG_ROOT")
    }


def test_registering_a_model_leaves_no_mlflow_db_in_the_working_folder(tmp_path):
    import json

    cwd, root = tmp_path / "cwd", tmp_path / "root"
    cwd.mkdir()
    root.mkdir()
    done = subprocess.run(
        [sys.executable, "-c", REGISTER_THEN_RUN, str(root)],
        cwd=cwd,
        env=_clean_env(),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stdout + done.stderr[-3000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert sorted(p.name for p in cwd.iterdir()) == [], "MLflow wrote into the working folder"
    assert result["env"] is None  # the registry's URI is not left behind for later runs
    assert result["store"].startswith(f"sqlite:///{root.resolve() / 'mlruns.db'}")
    assert (root / "mlruns.db").is_file()


def test_a_tracking_uri_set_before_registering_is_restored(tmp_path):
    """A URI set before (Lightning's logger sets the training store's) is the one afterwards."""
    script = textwrap.dedent(
        """
        import os, sys
        import mlflow
        from prg.serving import _tracking
        from prg.tracking import sqlite_uri

        mlflow.set_tracking_uri(sqlite_uri(sys.argv[1] + "/before.db"))
        with _tracking(sqlite_uri(sys.argv[1] + "/registry.db")):
            pass
        print(mlflow.get_tracking_uri())
        print(os.environ["MLFLOW_TRACKING_URI"])
        """
    )
    done = subprocess.run(
        [sys.executable, "-c", script, str(tmp_path)],
        cwd=tmp_path,
        env=_clean_env(),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    before = f"sqlite:///{Path(tmp_path).resolve() / 'before.db'}?timeout=60"
    assert done.stdout.split() == [before, before]
    assert not (tmp_path / "mlflow.db").exists()
