"""Trained models as MLflow models: served over HTTP (``mlflow models serve``), loaded anywhere
with ``mlflow.pyfunc.load_model``, registered with their evaluation metrics.

A logged model is a **pyfunc around the library's writer** (:class:`WriterModel`: a
:class:`prg.writer.Writer` on the run's best checkpoint), not the PyTorch flavour: what a caller
wants from a PRG model is a written word — decoded letters, layout, connection strokes and the
word's DMP — and the network alone gives none of that; a PyTorch-flavour model would leave every
caller to re-implement the generation stage. It is logged *from code* (``writer_model.py``,
MLflow's models-from-code): the model folder holds that file and the checkpoint, which is read as
data (``torch.load(weights_only=True)``), so loading a model never unpickles code.

Input: a table with a ``text`` column (the word) and/or a ``trajectories`` column (a JSON list
with one pen stroke per letter, each a list of ``[x, y]``, y up): a row with only trajectories is
read by the model, as ``prg-write trajectories=...``. Output, one row per input row, JSON-able:
``text`` (the written word), ``duration_s``, ``path_length_cm``, ``word`` (the
``prg.word_trajectory`` JSON document: points, segment kinds, timing and DMP;
``WordTrajectory.from_dict(json.loads(word))`` reads it back) and ``rollout`` (JSON ``[[x, y],
...]`` in cm: the DMP's rollout of the cursive body on its own time grid).
"""

from __future__ import annotations

import contextlib
import json
import math
from pathlib import Path
from typing import Any

from prg.errors import UsageError

__all__ = [
    "CHAMPION",
    "INPUT_EXAMPLE",
    "WriterModel",
    "champion_metric",
    "log_writer_model",
    "register_version",
    "signature",
    "word_row",
]

CODE = Path(__file__).with_name("writer_model.py")
"""The models-from-code file MLflow copies into every logged model."""
INPUT_EXAMPLE = {"text": ["cat"]}
MODEL_URI_TAG = "prg.model_uri"
"""Run tag: the ``models:/<id>`` URI of the run's logged model."""
CHAMPION = "champion"
"""The alias of the registered version that is best by :func:`champion_metric`."""
OUTPUT_COLUMNS = ("text", "duration_s", "path_length_cm", "word", "rollout")


def signature():
    """The model's MLflow signature: optional ``text`` and ``trajectories`` strings in; the
    written word's columns out."""
    from mlflow.models import ModelSignature
    from mlflow.types import ColSpec, Schema

    inputs = Schema(
        [
            ColSpec("string", "text", required=False),
            ColSpec("string", "trajectories", required=False),
        ]
    )
    outputs = Schema(
        [
            ColSpec("string", "text"),
            ColSpec("double", "duration_s"),
            ColSpec("double", "path_length_cm"),
            ColSpec("string", "word"),
            ColSpec("string", "rollout"),
        ]
    )
    return ModelSignature(inputs=inputs, outputs=outputs)


def word_row(result) -> dict[str, Any]:
    """One output row of a :class:`prg.writer.WriteResult`."""
    word = result.word
    return {
        "text": word.text,
        "duration_s": float(word.duration_s),
        "path_length_cm": float(word.path_length),
        "word": json.dumps(word.to_dict()),
        "rollout": json.dumps(result.rollout.round(6).tolist()),
    }


def _given(value: Any) -> Any:
    """None for a missing cell (absent column, None, NaN), else the value."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return None
    return value


def _strokes(value: str, row: int) -> list:
    import numpy as np

    try:
        strokes = [np.asarray(s, dtype=np.float64) for s in json.loads(value)]
    except (TypeError, ValueError):
        raise UsageError(
            f"row {row}: trajectories must be a JSON list of strokes, one per letter, "
            "each a list of [x, y]"
        ) from None
    return strokes


class WriterModel:
    """The pyfunc model: ``predict(table)`` writes each row's word (module docstring).

    A plain class with the pyfunc protocol (``load_context``, ``predict``); ``writer_model.py``
    makes it an ``mlflow.pyfunc.PythonModel``, so that importing :mod:`prg.serving` does not
    import MLflow.
    """

    writer = None

    def load_context(self, context) -> None:
        from prg.writer import Writer

        self.writer = Writer.from_checkpoint(context.artifacts["checkpoint"])

    def predict(self, context, model_input, params=None):
        import pandas as pd

        frame = pd.DataFrame(model_input)
        unknown = sorted(set(frame.columns) - {"text", "trajectories"})
        if unknown or frame.empty:
            raise UsageError(
                f"input: expected rows with a text and/or a trajectories column, got columns "
                f"{list(frame.columns)}"
            )
        rows = []
        for i, row in enumerate(frame.to_dict("records")):
            text, trajectories = _given(row.get("text")), _given(row.get("trajectories"))
            if text is None and trajectories is None:
                raise UsageError(f"row {i}: give a text, trajectories or both")
            result = self.writer.write(
                text=text,
                trajectories=None if trajectories is None else _strokes(trajectories, i),
            )
            rows.append(word_row(result))
        return pd.DataFrame(rows, columns=list(OUTPUT_COLUMNS))


def log_writer_model(checkpoint: str | Path, run_id: str, tracking_uri: str) -> str:
    """Log ``checkpoint`` as the run's MLflow model ``model`` (:class:`WriterModel`, with its
    signature and an input example); returns its ``models:/<model_id>`` URI.

    The run stays as it was (this resumes it only to attach the model, and leaves its status).
    Requirements are pinned to this installation's ``prg`` (no dependency inference: it would
    import and trace the code in a subprocess, for seconds).
    """
    import mlflow
    from mlflow import MlflowClient

    client = MlflowClient(tracking_uri)
    status = client.get_run(run_id).info.status
    with _tracking(tracking_uri), mlflow.start_run(run_id=run_id):
        info = mlflow.pyfunc.log_model(
            name="model",
            python_model=str(CODE),
            artifacts={"checkpoint": str(checkpoint)},
            signature=signature(),
            input_example=INPUT_EXAMPLE,
            pip_requirements=[f"prg=={_version()}"],
        )
    client.update_run(run_id, status=status)  # start_run's end marked it FINISHED
    client.set_tag(run_id, MODEL_URI_TAG, info.model_uri)
    return info.model_uri


def champion_metric(family: str, metrics: dict[str, float]) -> tuple[str, bool]:
    """(metric, higher is better) that picks the champion among a family's versions: the folded
    coherence of trajectories from the label (from the image for AVAE(T,I), which has no label)
    when the version carries evaluation metrics, else the validation loss (lower is better)."""
    given = "I" if family == "avae_ti" else "S"
    coherence = f"coherence_folded_T_given_{given}"
    return (coherence, True) if coherence in metrics else ("val_loss", False)


def register_version(name: str, run_id: str, tracking_uri: str, metrics: dict[str, float]) -> str:
    """Register the run's logged model as a version of ``name``, tag it with ``metrics``
    (``metric.<key>``) and move the :data:`CHAMPION` alias to the best version; returns the
    version number. A run registered before keeps its version, whose tags are updated (so
    registering after each ``make demo`` adds no duplicates)."""
    from mlflow import MlflowClient
    from mlflow.exceptions import MlflowException

    client = MlflowClient(tracking_uri)
    run = client.get_run(run_id)
    model_uri = run.data.tags.get(MODEL_URI_TAG)
    if model_uri is None:
        raise UsageError(
            f"run {run_id} has no logged model (tag {MODEL_URI_TAG}): train with log_model=true"
        )
    with contextlib.suppress(MlflowException):  # registered already: add a version
        client.create_registered_model(name)
    family = run.data.tags.get("prg.family", "")
    existing = [
        v
        for v in client.search_model_versions(f"name = '{name}'")
        if v.run_id == run_id and v.source == model_uri
    ]
    if existing:
        version = existing[0].version
    else:
        model_id = model_uri.removeprefix("models:/")
        with _tracking(tracking_uri):  # the registry resolves models:/ in the global store
            version = client.create_model_version(
                name, source=model_uri, run_id=run_id, model_id=model_id
            ).version
    for key, value in sorted(metrics.items()):
        if isinstance(value, int | float) and math.isfinite(value):
            client.set_model_version_tag(name, version, f"metric.{key}", f"{value:.6g}")
    client.set_model_version_tag(name, version, "prg.family", family)
    _move_champion(client, name, family)
    return str(version)


def _move_champion(client, name: str, family: str) -> None:
    scored = []
    for version in client.search_model_versions(f"name = '{name}'"):
        metrics = {
            k.removeprefix("metric."): float(v)
            for k, v in version.tags.items()
            if k.startswith("metric.")
        }
        metric, higher = champion_metric(family, metrics)
        if metric in metrics:
            sign = 1.0 if higher else -1.0
            scored.append((metric == "val_loss", -sign * metrics[metric], int(version.version)))
    if scored:  # evaluated versions first, then the best value, then the newest
        best = min(scored, key=lambda t: (t[0], t[1], -t[2]))
        client.set_registered_model_alias(name, CHAMPION, str(best[2]))


@contextlib.contextmanager
def _tracking(uri: str):
    """MLflow's global tracking URI set to ``uri`` for the block (the fluent API and the
    registry's ``models:/`` resolution read it), then restored; MLflow's artifact progress bars
    off meanwhile: logging a model downloads its artifacts to validate the input example, and
    those bars would take the place of the training's own progress bar in its output.

    A URI that was not set before is unset again, not set to what ``mlflow.get_tracking_uri()``
    answers then (MLflow 3's default, ``sqlite:///mlflow.db`` in the working folder):
    ``set_tracking_uri`` also exports ``MLFLOW_TRACKING_URI``, which :func:`prg.tracking.tracking_uri`
    puts first, so every later run of the process and of its children would go to that file."""
    import os

    import mlflow

    previous = mlflow.get_tracking_uri() if mlflow.is_tracking_uri_set() else None
    bars = os.environ.get("MLFLOW_ENABLE_ARTIFACTS_PROGRESS_BAR")
    mlflow.set_tracking_uri(uri)
    os.environ["MLFLOW_ENABLE_ARTIFACTS_PROGRESS_BAR"] = "false"
    try:
        yield
    finally:
        mlflow.set_tracking_uri(previous)  # None: unset, MLFLOW_TRACKING_URI removed with it
        if bars is None:
            os.environ.pop("MLFLOW_ENABLE_ARTIFACTS_PROGRESS_BAR", None)
        else:
            os.environ["MLFLOW_ENABLE_ARTIFACTS_PROGRESS_BAR"] = bars


def _version() -> str:
    from importlib.metadata import version

    return version("prg")
