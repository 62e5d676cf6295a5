"""The training runs' logger: Lightning's MLflow logger on the configured store (Hydra's
``logger`` config group: ``_target_: prg.tracking.mlflow_logger``)."""

from __future__ import annotations

from prg.tracking.store import get_experiment_id, is_server, mlflow_client


def mlflow_logger(
    experiment_name: str,
    run_name: str,
    tracking_uri: str,
    artifact_location: str,
    run_id: str | None = None,
    tags: dict[str, str] | None = None,
    task_experiment_name: str | None = None,
):
    """A Lightning MLflow logger on an explicit store (never the default ./mlruns), logging to
    the training experiment (``task_experiment_name`` is the other commands') with the project's
    metric names (:class:`prg.training.mlflow_logger.LetterNamedMLFlowLogger`)."""
    from prg.training.mlflow_logger import LetterNamedMLFlowLogger

    get_experiment_id(mlflow_client(tracking_uri), experiment_name, artifact_location)
    return LetterNamedMLFlowLogger(
        experiment_name=experiment_name,
        run_name=None if run_id else run_name,
        tracking_uri=tracking_uri,
        artifact_location=None if is_server(tracking_uri) else artifact_location,
        run_id=run_id,
        tags=None if run_id else tags,
        log_model=False,
    )
