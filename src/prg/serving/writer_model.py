"""MLflow models-from-code: the pyfunc model of a trained PRG checkpoint (see prg.serving).

MLflow copies this file into each logged model and runs it on loading; it defines no state of
its own: the checkpoint is the model's ``checkpoint`` artifact, read as data.
"""

import mlflow
from mlflow.pyfunc import PythonModel

from prg.serving import WriterModel


class PyfuncWriterModel(WriterModel, PythonModel):
    """:class:`prg.serving.WriterModel` as an ``mlflow.pyfunc.PythonModel``."""


mlflow.models.set_model(PyfuncWriterModel())
