"""``PRGOptunaSweeper``: Hydra multirun jobs proposed by an Optuna study (package docstring).

Search space: ``hydra.sweeper.params`` (and any sweep on the command line) in Hydra's sweep
grammar, mapped onto Optuna distributions::

    choice(64, 128, 256)            -> categorical
    range(1, 5)                     -> categorical over the range's values
    interval(1e-4, 3e-3)            -> float, uniform
    tag(log, interval(1e-4, 3e-3))  -> float, log-uniform
    tag(int, interval(1, 8))        -> integer (tag(int, log, ...): log-uniform integer)

Each job's return value is its task's (``prg-train`` returns the run's final metrics); the
``objective`` metric of it is told to the study (``direction`` minimize or maximize). A job that
fails or lacks the metric is told as a failed trial and the search goes on. The study lives in
``storage`` (an SQLite URL: ``optuna-dashboard sqlite:///...`` opens it) under ``study_name``,
resumed when it exists; the best trial is written to ``<sweep dir>/optimization_results.yaml``.
"""

# no `from __future__ import annotations`: Hydra executes plugin modules outside sys.modules,
# where a dataclass cannot resolve string annotations
import logging
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hydra.core.config_store import ConfigStore
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.core.override_parser.types import (
    ChoiceSweep,
    IntervalSweep,
    Override,
    RangeSweep,
)
from hydra.core.plugins import Plugins
from hydra.errors import CompactHydraException
from hydra.plugins.sweeper import Sweeper
from hydra.types import HydraContext, TaskFunction
from omegaconf import DictConfig, OmegaConf

log = logging.getLogger(__name__)

DIRECTIONS = ("minimize", "maximize")


@dataclass
class PRGOptunaSweeperConf:
    _target_: str = "hydra_plugins.prg_optuna_sweeper.sweeper.PRGOptunaSweeper"
    objective: str = "val/loss"  # the metric of the job's return value to optimise
    direction: str = "minimize"
    study_name: str = "prg"
    storage: str | None = None  # e.g. sqlite:///optuna.db; None: in memory
    n_trials: int = 20
    n_jobs: int = 1  # trials proposed at once, launched as one batch
    seed: int | None = None  # the TPE sampler's seed
    n_startup_trials: int = 10  # TPE: random trials before it models the space
    params: dict[str, str] = field(default_factory=dict)


ConfigStore.instance().store(
    group="hydra/sweeper", name="prg_optuna", node=PRGOptunaSweeperConf, provider="prg"
)


class SearchError(CompactHydraException):
    """A search that cannot run as configured: Hydra prints its one line, no traceback."""


def distribution(override: Override) -> Any:
    """The Optuna distribution of one sweep override (module docstring), or None when the
    override is a plain value."""
    import optuna.distributions as dist

    if not override.is_sweep_override():
        return None
    value = override.value()
    key = override.get_key_element()
    if isinstance(value, ChoiceSweep):
        return dist.CategoricalDistribution([_plain(v) for v in value.list])
    if isinstance(value, RangeSweep):
        return dist.CategoricalDistribution(list(value.range()))
    if isinstance(value, IntervalSweep):
        low, high, log = value.start, value.end, "log" in value.tags
        if "int" in value.tags:
            return dist.IntDistribution(int(low), int(high), log=log)
        return dist.FloatDistribution(float(low), float(high), log=log)
    raise SearchError(f"{key}: a sweep the Optuna sweeper cannot search ({value!r})")


def _plain(value: Any) -> Any:
    if value is None or isinstance(value, bool | int | float | str):
        return value
    return str(value)


class PRGOptunaSweeper(Sweeper):
    def __init__(
        self,
        objective: str,
        direction: str,
        study_name: str,
        storage: str | None,
        n_trials: int,
        n_jobs: int,
        seed: int | None,
        n_startup_trials: int,
        params: dict[str, str] | None,
    ) -> None:
        if direction not in DIRECTIONS:
            raise SearchError(
                f"hydra.sweeper.direction: expected minimize or maximize, got {direction!r}"
            )
        if n_trials < 1 or n_jobs < 1:
            raise SearchError("hydra.sweeper.n_trials and n_jobs: expected integers >= 1")
        self.objective, self.direction = objective, direction
        self.study_name, self.storage = study_name, storage
        self.n_trials, self.n_jobs, self.seed = n_trials, n_jobs, seed
        self.n_startup_trials = n_startup_trials
        self.params = dict(params or {})
        self.config: DictConfig | None = None
        self.launcher = None
        self.job_idx = 0

    def setup(
        self, *, hydra_context: HydraContext, task_function: TaskFunction, config: DictConfig
    ) -> None:
        self.config = config
        self.hydra_context = hydra_context  # validate_batch_is_legal composes with its loader
        self.launcher = Plugins.instance().instantiate_launcher(
            hydra_context=hydra_context, task_function=task_function, config=config
        )

    def _space(self, arguments: list[str]) -> tuple[list[str], dict[str, Any]]:
        """(fixed overrides, name -> distribution) from the configured params and the command
        line (the command line wins for a key given in both)."""
        parser = OverridesParser.create()
        given = [f"{k}={v}" for k, v in self.params.items()] + list(arguments)
        fixed: dict[str, str] = {}
        space: dict[str, Any] = {}
        for override in parser.parse_overrides(given):
            key = override.get_key_element()
            space.pop(key, None)
            fixed.pop(key, None)
            found = distribution(override)
            if found is None:
                fixed[key] = override.input_line
            else:
                space[key] = found
        if not space:
            raise SearchError(
                "the Optuna sweeper has nothing to search: give hydra.sweeper.params "
                "(e.g. hparams_search=muse_optuna) or a sweep such as lr=interval(1e-4,3e-3)"
            )
        return list(fixed.values()), space

    def sweep(self, arguments: list[str]) -> Any:
        import optuna
        from optuna.trial import TrialState

        assert self.config is not None and self.launcher is not None
        fixed, space = self._space(arguments)
        sweep_dir = Path(self.config.hydra.sweep.dir)
        sweep_dir.mkdir(parents=True, exist_ok=True)
        OmegaConf.save(self.config, sweep_dir / "multirun.yaml")
        study = optuna.create_study(
            study_name=self.study_name,
            storage=self.storage,
            direction=self.direction,
            sampler=optuna.samplers.TPESampler(
                seed=self.seed, n_startup_trials=self.n_startup_trials
            ),
            load_if_exists=True,
        )
        log.info(
            "Optuna study %r (%s): %d trials over %s",
            self.study_name,
            self.storage or "in memory",
            self.n_trials,
            ", ".join(space),
        )
        done = 0
        while done < self.n_trials:
            trials = [study.ask(space) for _ in range(min(self.n_jobs, self.n_trials - done))]
            batch = [(*fixed, *(f"{key}={trial.params[key]}" for key in space)) for trial in trials]
            self.validate_batch_is_legal(batch)
            returns = self.launcher.launch(batch, initial_job_idx=self.job_idx)
            self.job_idx += len(batch)
            for trial, job in zip(trials, returns):
                value = _objective(job, self.objective)
                if value is None:
                    study.tell(trial, state=TrialState.FAIL)
                    log.warning("trial %d failed or gave no %s", trial.number, self.objective)
                else:
                    study.tell(trial, value)
            done += len(batch)
        finished = [t for t in study.trials if t.state == TrialState.COMPLETE]
        if not finished:
            raise SearchError(f"no trial of study {self.study_name!r} completed")
        best = study.best_trial
        results = {
            "name": "optuna",
            "study_name": self.study_name,
            "storage": self.storage,
            "objective": self.objective,
            "direction": self.direction,
            "best_params": best.params,
            "best_value": best.value,
            "best_trial": best.number,
            "trials": len(study.trials),
        }
        OmegaConf.save(OmegaConf.create(results), sweep_dir / "optimization_results.yaml")
        log.info("best %s = %s with %s", self.objective, best.value, best.params)
        return results


def _objective(job: Any, key: str) -> float | None:
    """The objective of a job's return value: its ``key`` entry (a mapping of metrics) or the
    value itself (a number); None when the job failed or the value is not a finite number."""
    try:
        value = job.return_value  # raises the job's exception when it failed
    except Exception:
        log.exception("a trial's job failed")
        return None
    if isinstance(value, dict):
        value = value.get(key)
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return number if math.isfinite(number) else None
