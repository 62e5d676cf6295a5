"""Settings of a training run that are checked against each other before anything is built.

The numeric options of ``prg-train`` (``seed``, ``model.batch_size``, ``trainer.*`` ...) are
checked by :func:`prg.checks.check_values`; what a range cannot say is checked here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from prg.errors import SettingsError


@dataclass(frozen=True)
class TrainSettings:
    """The model family a run fits and the modalities the data provide for it.

    Attributes
    ----------
    model
        the family's name (``model.name``).
    modalities
        the modalities the model takes (``model.modalities``).
    provided
        the modalities the dataset provides (``data.loader.modalities``); every one of
        ``modalities`` must be among them.
    """

    model: str
    modalities: Sequence[str]
    provided: Sequence[str]

    def __post_init__(self) -> None:
        object.__setattr__(self, "modalities", tuple(self.modalities))
        object.__setattr__(self, "provided", tuple(self.provided))
        missing = [m for m in self.modalities if m not in self.provided]
        if missing:
            raise SettingsError(
                "model",
                f"{self.model} needs modalities {list(self.modalities)} but the data provides "
                f"{list(self.provided)} (data.loader.modalities): {missing} missing",
            )
