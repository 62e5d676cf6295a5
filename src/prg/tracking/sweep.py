"""A Hydra multirun's MLflow parent run (:class:`SweepParentRun`, the Hydra callback enabled in
``conf/hydra/default.yaml``): opened when the sweep starts, its id exported in
``PRG_PARENT_RUN_ID`` so that each job's run is tagged ``mlflow.parentRunId``.

The same sweep run again (a stopped sweep's command, whose finished jobs ``prg-train`` skips and
whose interrupted ones it resumes: ``resume``) continues its earlier parent run instead of opening
a second one: a parent is tagged ``prg.sweep.key`` (:func:`sweep_key`: the command, its sorted
overrides and its composed config), and the newest parent with the key is reused, set RUNNING
until the sweep ends. Not with ``resume=never``, nor for a command without a ``resume`` option
(its jobs always run again, so they get a new parent)."""

from __future__ import annotations

import hashlib
import json
import logging
import os
import time
from typing import Any

from hydra.experimental.callback import Callback as HydraCallback
from omegaconf import DictConfig, OmegaConf

from prg.tracking.naming import DESCRIPTION_TAG, PARENT_ENV
from prg.tracking.store import experiment_of, mlflow_client, tracking_uri

log = logging.getLogger(__name__)
KEY_TAG = "prg.sweep.key"


def sweep_key(config: DictConfig) -> str:
    """What makes two multiruns the same sweep: the command (config name), its task overrides in
    any order and its composed config (the ``hydra`` node left out), as a SHA-256."""
    body = OmegaConf.masked_copy(config, [k for k in config if k != "hydra"])
    try:
        composed = OmegaConf.to_container(body, resolve=True)
    except Exception:  # an unresolvable value fails in the jobs, with its own message
        composed = OmegaConf.to_container(body, resolve=False)
    text = json.dumps(
        {
            "command": config.hydra.job.config_name,
            "overrides": sorted(config.hydra.overrides.task),
            "config": composed,
        },
        sort_keys=True,
        default=str,
    )
    return hashlib.sha256(text.encode()).hexdigest()


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
        key = sweep_key(config)
        previous = None
        if config.get("resume", "never") != "never":  # its finished jobs are skipped, not re-run
            found = self.client.search_runs(
                [experiment_id],
                filter_string=f"tags.`{KEY_TAG}` = '{key}'",
                order_by=["attributes.start_time DESC"],
                max_results=1,
            )
            previous = found[0] if found else None
        if previous is not None:
            self.client.update_run(previous.info.run_id, status="RUNNING")
            log.info(
                "the same sweep again: continuing its parent MLflow run %s", previous.info.run_id
            )
            self.run_id = previous.info.run_id
        else:
            run = self.client.create_run(
                experiment_id,
                run_name=f"sweep {time.strftime('%Y-%m-%d %H:%M:%S')}",
                tags={
                    "prg.sweep": "parent",
                    "prg.sweep.overrides": overrides[:5000],
                    KEY_TAG: key,
                    DESCRIPTION_TAG: "A sweep: its jobs are the child runs.  \n"
                    f"Command: `{command}`",
                },
            )
            self.run_id = run.info.run_id
        os.environ[PARENT_ENV] = self.run_id

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        if self.run_id is not None:
            self.client.set_terminated(self.run_id)
            os.environ.pop(PARENT_ENV, None)
            self.run_id = None
