"""Lightning's MLflow logger with the project's metric names (:func:`prg.tracking.metric_name`)."""

from __future__ import annotations

from collections.abc import Mapping

from lightning.pytorch.loggers import MLFlowLogger

from prg.tracking import metric_name


class LetterNamedMLFlowLogger(MLFlowLogger):
    """Lightning's ``MLFlowLogger`` that names modalities by the paper's letters in the metrics it
    sends (``train/rec_traj`` -> ``train/rec_T``); the trainer's own metric names are unchanged."""

    def log_metrics(self, metrics: Mapping[str, float], step: int | None = None) -> None:
        super().log_metrics({metric_name(k): v for k, v in metrics.items()}, step)
