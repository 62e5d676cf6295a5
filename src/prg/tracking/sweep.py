"""A Hydra multirun's MLflow parent run (:class:`SweepParentRun`, the Hydra callback enabled in
``conf/hydra/default.yaml``): opened when the sweep starts, its id exported in
``PRG_PARENT_RUN_ID`` so that each job's run is tagged ``mlflow.parentRunId``."""

from __future__ import annotations

import os
import time
from typing import Any

from hydra.experimental.callback import Callback as HydraCallback
from omegaconf import DictConfig

from prg.tracking.naming import DESCRIPTION_TAG, PARENT_ENV
from prg.tracking.store import experiment_of, mlflow_client, tracking_uri


class SweepParentRun(HydraCallback):
    """Hydra callback: one MLflow parent run per multirun; jobs attach to it as children."""

    def __init__(self, enabled: bool = True):
        self.enabled = enabled
        self.run_id: str | None = None
        self.client = None

    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        if not self.enabled or "logger" not in config or os.environ.get(PARENT_ENV):
            return
        uri = tracking_uri(config.logger.get("tracking_uri"), config.paths.root_dir)
        self.client = mlflow_client(uri)
        # a sweep of prg-train groups training runs; of another command, that command's runs
        experiment_id = experiment_of(self.client, config, tasks="trainer" not in config)
        overrides = " ".join(config.hydra.overrides.task)
        command = f"prg-{config.hydra.job.config_name} -m {overrides}"
        run = self.client.create_run(
            experiment_id,
            run_name=f"sweep {time.strftime('%Y-%m-%d %H:%M:%S')}",
            tags={
                "prg.sweep": "parent",
                "prg.sweep.overrides": overrides[:5000],
                DESCRIPTION_TAG: f"A sweep: its jobs are the child runs.  \nCommand: `{command}`",
            },
        )
        self.run_id = run.info.run_id
        os.environ[PARENT_ENV] = self.run_id

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        if self.run_id is not None:
            self.client.set_terminated(self.run_id)
            os.environ.pop(PARENT_ENV, None)
            self.run_id = None
