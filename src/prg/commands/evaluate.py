"""``prg-evaluate``: Table I log-likelihoods, cross-modal coherence and robustness of trained models.

Examples
--------
``prg-evaluate``                                        the DVC models (``models/<family>/model.ckpt``)
``prg-evaluate families=[muse] likelihood.k_conditional=500``
``prg-evaluate +checkpoints.mine=checkpoints/prg/muse-seed0/best.ckpt``   any checkpoints
``prg-evaluate parts=[classifiers]``                    only train the coherence classifiers
``prg-evaluate likelihood.cells=[logp_T,logp_T_given_S] parts=[likelihood]``

Writes ``reports/table1.{md,csv}``, ``reports/coherence.{md,csv}``, ``reports/robustness.md``,
``reports/metrics.json`` and ``reports/figures/``; metrics also go to MLflow, into each model's
training run (``test/logp_T_given_S``, ``test/coherence_T_given_S`` ...) and into one
``evaluate`` run that holds the reports as artifacts. The metric keys are listed in
:mod:`prg.evaluation.run`, which holds the evaluation itself; this module reads the config,
writes the reports and logs the runs.
"""

from __future__ import annotations

import logging
from pathlib import Path

from omegaconf import DictConfig, OmegaConf

from prg.checks import check_values
from prg.commands.cli import check_output
from prg.commands.settings import build, node
from prg.errors import UsageError
from prg.evaluation.classifiers import ensure_classifiers
from prg.evaluation.figures import evaluation_figures
from prg.evaluation.reports import report_texts, title
from prg.evaluation.run import (
    Evaluation,
    LoadedModel,
    check_cells,
    load_models,
    load_test_data,
    run_evaluation,
)
from prg.evaluation.second_readers import ensure_second_readers
from prg.evaluation.settings import (
    ClassifierSettings,
    CoherenceSettings,
    EvaluationSettings,
    KinematicsSettings,
    LikelihoodSettings,
    LikenessSettings,
    StyleSettings,
)
from prg.files import staged_outputs, write_json, write_text
from prg.resources import git_commit, project_path
from prg.tracking import TaskRun, experiment_of, metric_name, task_run

log = logging.getLogger(__name__)


# ---- the config ------------------------------------------------------------------------------
def evaluation_settings(cfg: DictConfig) -> EvaluationSettings:
    """The evaluation's settings from the config nodes, a refused value named by its path."""
    classifier = node(cfg, "classifier")
    classifier.pop("dir")
    return build(
        EvaluationSettings,
        {
            "parts": list(cfg.parts),
            "seed": cfg.seed,
            "n_test": cfg.n_test,
            "progress": cfg.progress,
            "figures": cfg.figures,
        },
        None,
        likelihood=build(LikelihoodSettings, node(cfg, "likelihood"), "likelihood"),
        coherence=build(CoherenceSettings, node(cfg, "coherence"), "coherence"),
        classifier=build(ClassifierSettings, classifier, "classifier"),
        likeness=build(LikenessSettings, node(cfg, "likeness"), "likeness"),
        styles=build(StyleSettings, node(cfg, "styles"), "styles"),
        kinematics=build(KinematicsSettings, node(cfg, "kinematics"), "kinematics"),
    )


def dataset_dir(cfg: DictConfig) -> Path:
    """The prepared dataset folder: ``<paths.data_dir>/prepared/<data.name>``."""
    return Path(cfg.paths.data_dir) / "prepared" / cfg.data.name


def checkpoint_paths(cfg: DictConfig) -> dict[str, Path]:
    """name -> checkpoint: ``checkpoints`` when given, else each of ``families`` under
    ``models_dir``, which must exist."""
    if cfg.checkpoints:
        return {str(name): Path(path) for name, path in cfg.checkpoints.items()}
    families = list(cfg.families)
    if not families:
        raise UsageError("nothing to evaluate: give families=[...] or +checkpoints.<name>=PATH")
    paths = {f: Path(cfg.models_dir) / f / "model.ckpt" for f in families}
    missing = [str(p) for p in paths.values() if not p.is_file()]
    if missing:
        raise UsageError(
            f"checkpoint {missing[0]} does not exist: train it first (`dvc repro train` or "
            "`prg-train model=<family> export_dir=...`), or choose families=[...] / "
            "+checkpoints.<name>=PATH"
        )
    return paths


# ---- the task --------------------------------------------------------------------------------
def evaluate(cfg: DictConfig) -> Evaluation:
    """Task: run the requested parts on the configured checkpoints and write the reports."""
    check_values(cfg)
    settings = evaluation_settings(cfg)
    data_dir = dataset_dir(cfg)
    classifier_dir = Path(cfg.classifier.dir)
    if settings.classifiers_only:
        check_output(classifier_dir, "classifier.dir")
        classifiers = ensure_classifiers(
            data_dir, classifier_dir, settings.classifier, progress=settings.progress
        )
        ensure_second_readers(data_dir, classifier_dir, classifiers, settings.classifier.seed)
        return Evaluation()
    report_dir = check_output(cfg.report_dir, "report_dir")
    models = load_models(checkpoint_paths(cfg))
    test = load_test_data(data_dir)
    check_cells(models, settings)
    tags = {"prg.git_commit": git_commit(), "prg.data.name": cfg.data.name}
    with task_run(cfg, "evaluate", tags) as run:
        result = run_evaluation(models, test, settings, data_dir, classifier_dir)
        result.report_dir = _write_reports(result, models, test, settings, report_dir, cfg)
        _log_run(run, result, models, cfg)
    log.info("reports in %s", result.report_dir)
    for name, (model, _, _) in models.items():
        log.info("%s: %s", name, title(model.family))
    return result


def _write_reports(result, models, test, settings, report_dir: Path, cfg: DictConfig) -> Path:
    """Every report, through a staging folder, into ``report_dir``."""
    root = cfg.paths.root_dir  # the reports name project files from its root (project_path)
    checkpoints = {name: project_path(loaded.path, root) for name, loaded in models.items()}
    with staged_outputs(report_dir) as staging:
        for name, text in report_texts(result, settings, checkpoints, cfg.data.name).items():
            (staging / name).parent.mkdir(exist_ok=True)  # plots/
            write_text(staging / name, text, atomic=False)
        if "coherence" in settings.parts and settings.figures:
            (staging / "figures").mkdir()
            trained = {name: loaded.model for name, loaded in models.items()}
            evaluation_figures(trained, result.per_class, test, staging / "figures", result.readers)
        write_json(staging / "metrics.json", result.metrics)
    return report_dir


def _log_run(run: TaskRun, result: Evaluation, models: dict[str, LoadedModel], cfg) -> None:
    """Metrics into each model's training run (when in this store: else a ``<name>-evaluate``
    run in the training experiment) and into this ``evaluate`` run, with the config and the
    reports as artifacts; modalities named by the paper's letters (``classifier/T/...``)."""
    from mlflow.exceptions import MlflowException

    client = run.client
    for name, (model, info, path) in models.items():
        metrics = {
            k.split("/", 1)[1]: v for k, v in result.metrics.items() if k.startswith(f"{name}/")
        }
        run_id = info.get("mlflow_run_id")
        try:
            if not run_id:
                raise MlflowException("no run id in the checkpoint")
            client.get_run(run_id)
        except MlflowException:
            experiment = experiment_of(client, cfg, tasks=False)  # beside the training runs
            run_id = client.create_run(
                experiment, run_name=f"{name}-evaluate", tags={"prg.family": model.family}
            ).info.run_id
            client.set_terminated(run_id)
        TaskRun(client, run_id).log_metrics(metrics, prefix="test/")
        client.set_tag(run_id, "prg.evaluated_checkpoint", str(path))
    run.log_metrics({metric_name(k): v for k, v in result.metrics.items()}, prefix="test/")
    run.log_text(OmegaConf.to_yaml(cfg, resolve=True), "config/config.yaml")
    run.log_artifacts(result.report_dir, "reports")


if __name__ == "__main__":
    from prg.commands.entry import evaluate

    evaluate()
