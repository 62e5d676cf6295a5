"""Settings of an evaluation (``conf/evaluate.yaml``), each class checking its own fields.

A refused value raises :class:`~prg.errors.SettingsError` naming the field (``k_marginal``); the
command layer (:mod:`prg.commands.evaluate`) adds the config path (``likelihood.k_marginal``).
Each numeric field declares the values it accepts (:func:`prg.fields.ranged`): the dataclass
checks them (:func:`prg.fields.check_fields`) and :data:`prg.checks.RANGES` takes its
``likelihood.*``, ``coherence.*``, ``classifier.*``, ``likeness.*`` and ``styles.*`` entries from
them (:data:`prg.checks.DECLARED`). The options holding several numbers (``coherence.temperatures``,
``coherence.image_shifts``, ``styles.ks``, ``styles.seeds``) and the top-level ``seed`` and
``n_test``, which other commands share, keep their entries in :data:`prg.checks.TABLE`
(:class:`EvaluationSettings` declares its ``seed`` and ``n_test`` with the same ranges).

This module imports no numpy or torch (the Table I cells are read from
:mod:`prg.evaluation.likelihood` when a value is checked), so that ``prg-evaluate`` checks its
config before loading them; :data:`PAPER_TRAJ_STD` and :data:`DEFAULT_CFG` live here and
:mod:`prg.evaluation.likelihood` and :mod:`prg.evaluation.classifiers` export them too.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from prg.checks import (
    IMAGE_SHIFT,
    N_TEST,
    SEED,
    TEMPERATURE,
    Range,
    count,
    positive,
    require_number,
)
from prg.errors import SettingsError
from prg.fields import check_fields, ranged

PAPER_TRAJ_STD = 1.0
"""Trajectory std of Table I's main table: the reference code's implicit unit-variance Gaussian,
which puts log p(x_T) on the paper's scale (about -197 nats)."""

DEFAULT_CFG: dict[str, Any] = {"epochs": 4, "batch_size": 256, "lr": 2e-3, "seed": 0}
"""Default training settings of both classifiers (measured on 2 CPU cores with the full
synthetic dataset: 12 s for traj, 59 s for image; more epochs do not help on the test split)."""


def _table1_cells() -> dict[str, tuple[str, tuple[str, ...]]]:
    from prg.evaluation.likelihood import TABLE1_CELLS  # torch: imported when a value is checked

    return TABLE1_CELLS


PARTS = ("classifiers", "likelihood", "coherence", "likeness", "styles", "kinematics")
IMPUTED = "imputed"
"""The generation kind of samples decoded after imputing the missing modalities (MUSE)."""


@dataclass(frozen=True)
class LikelihoodSettings:
    """How Table I is estimated (``likelihood``).

    Attributes
    ----------
    cells
        ``"all"``, or the Table I cells to estimate (:data:`TABLE1_CELLS` names); named
        cells must be ones every evaluated model supports.
    k_marginal, k_conditional
        importance samples per test sample of ``log p(x_m)`` and of
        ``log p(x_a | x_b)`` (the paper's 1000 and 5000).
    n_test
        test samples (None: all; else a seeded subset).
    batch_size
        test samples per step.
    chunk_rows
        at most this many decoder outputs alive at
        once (bounds the memory).
    traj_std
        std of the trajectory Gaussian in the main table (None: each model's own).
    """

    cells: str | tuple[str, ...] = "all"
    k_marginal: int = ranged(1000, count(1, 1_000_000))
    k_conditional: int = ranged(5000, count(1, 1_000_000))
    n_test: int | None = ranged(None, N_TEST)
    batch_size: int = ranged(64, count(1, 100_000))
    chunk_rows: int = ranged(4096, count(1, 10_000_000))  # bounds the memory
    traj_std: float | None = ranged(PAPER_TRAJ_STD, Range(0, 100, low_open=True, optional=True))

    def __post_init__(self) -> None:
        check_fields(self)
        if self.cells != "all":
            TABLE1_CELLS = _table1_cells()
            cells = [self.cells] if isinstance(self.cells, str) else list(self.cells)
            unknown = [c for c in cells if c not in TABLE1_CELLS]
            if unknown or not cells:
                raise SettingsError(
                    "cells", f"{unknown or cells}: use 'all' or a list of {list(TABLE1_CELLS)}"
                )
            object.__setattr__(self, "cells", tuple(cells))

    @property
    def requested(self) -> tuple[list[str], bool]:
        """Table I cells to estimate, and whether they were named explicitly (then every model
        must support every one)."""
        if self.cells == "all":
            return list(_table1_cells()), False
        return list(self.cells), True


@dataclass(frozen=True)
class CoherenceSettings:
    """How generated samples are scored (``coherence``).

    Attributes
    ----------
    temperatures
        generation kind -> temperature (0: the posterior mean; 1: latents drawn with
        their std); the first kind is the robustness table's.
    impute_steps
        families that impute (MUSE) are also scored as the ``imputed`` kind, the
        posterior mean after this many rounds of imputing the missing modalities (0: not).
    batch_size
        test samples generated at once.
    image_shifts
        models that take an image alone are also scored on the test images moved
        off-centre by up to each of these many pixels per axis (a seeded random offset per
        image; the robustness report's second table); empty: not.
    """

    temperatures: Mapping[str, float] = field(default_factory=lambda: {"mean": 0.0, "sampled": 1.0})
    impute_steps: int = ranged(0, count(0, 1000))
    batch_size: int = ranged(512, count(1, 1_000_000))
    image_shifts: tuple[int, ...] = (1, 2)

    def __post_init__(self) -> None:
        spec = TEMPERATURE
        for kind, value in self.temperatures.items():
            require_number(value, f"temperatures.{kind}", spec)
        if IMPUTED in self.temperatures:
            # "temperatures:" keeps the message users know: "coherence.temperatures: 'imputed' ..."
            raise SettingsError("temperatures:", f"{IMPUTED!r} names the imputed kind; rename it")
        check_fields(self)
        for i, shift in enumerate(self.image_shifts):
            require_number(shift, f"image_shifts[{i}]", IMAGE_SHIFT)
        object.__setattr__(self, "temperatures", dict(self.temperatures))
        object.__setattr__(self, "image_shifts", tuple(self.image_shifts))


@dataclass(frozen=True)
class LikenessSettings:
    """How generated letters are compared with held-out writers' (``likeness``;
    :mod:`prg.evaluation.modes`).

    n_per_class : letters of each class generated per family and mode, and drawn from each
        reference split (at least 4: the k-NN measures use k = 3).
    references : the splits whose real letters are the reference rows (``val``: other
        held-out writers; ``train``: the training writers' originals).
    """

    # the k-NN measures need more than k = 3 letters a class
    n_per_class: int = ranged(10, count(4, 1000))
    references: tuple[str, ...] = ("val", "train")

    def __post_init__(self) -> None:
        check_fields(self)
        refs = tuple(self.references)
        if any(r not in ("train", "val") for r in refs):
            raise SettingsError("references", f"{list(refs)}: choose from ['train', 'val']")
        object.__setattr__(self, "references", refs)


@dataclass(frozen=True)
class StyleSettings:
    """How writing in a held-out writer's style is scored (``styles``;
    :mod:`prg.evaluation.styles`).

    ks : letters of the writer given as the style.
    seeds : repetitions (each sets other classes aside and draws other style letters).
    n_eval : classes set aside per seed: generated in the style and scored.
    temperature : the hand's std scale (``generate.hand_temperature``).
    """

    ks: tuple[int, ...] = (1, 5, 15)
    seeds: tuple[int, ...] = (0, 1, 2)
    # classes set aside: the rest train the writer classifier
    n_eval: int = ranged(12, count(1, 61))
    temperature: float = ranged(0.5, TEMPERATURE)

    def __post_init__(self) -> None:
        check_fields(self)
        for name in ("ks", "seeds"):
            values = tuple(getattr(self, name))
            if not values or any(
                isinstance(v, bool) or not isinstance(v, int) or v < (1 if name == "ks" else 0)
                for v in values
            ):
                low = "1" if name == "ks" else "0"
                raise SettingsError(name, f"{list(values)}: give a list of integers >= {low}")
            object.__setattr__(self, name, values)


@dataclass(frozen=True)
class KinematicsSettings:
    """How the pen's motion is measured (``kinematics``; :mod:`prg.evaluation.kinematics`).

    family : the model that writes the words (its checkpoint among the evaluated ones).
    words : written with the human timing and the paper's constant speed, planned and executed.
    robot : the simulated arm that executes them.
    """

    family: str = "muse"
    words: tuple[str, ...] = ("bell", "cat", "jump", "joy", "little", "letter")
    robot: str = "panda"

    def __post_init__(self) -> None:
        words = tuple(self.words)
        if not words or any(not isinstance(w, str) or not w.isalnum() for w in words):
            raise SettingsError("words", f"{list(words)}: give a list of words of 0-9, A-Z, a-z")
        object.__setattr__(self, "words", words)


@dataclass(frozen=True)
class ClassifierSettings:
    """How the coherence classifiers are trained (``classifier``, without its ``dir``;
    :func:`prg.evaluation.classifiers.ensure_classifiers`)."""

    epochs: int = ranged(DEFAULT_CFG["epochs"], count(1, 1000))
    batch_size: int = ranged(DEFAULT_CFG["batch_size"], count(1, 1_000_000))
    lr: float = ranged(DEFAULT_CFG["lr"], positive(10))
    seed: int = ranged(DEFAULT_CFG["seed"], SEED)

    def __post_init__(self) -> None:
        check_fields(self)


@dataclass(frozen=True)
class EvaluationSettings:
    """What ``prg-evaluate`` runs (the top level of ``conf/evaluate.yaml``).

    parts : some of :data:`PARTS`; ``classifiers`` alone only trains the classifiers.
    seed : seeds the test subsets, the importance samples and the generated samples.
    n_test : test samples for coherence and roughness (None: all; else a seeded subset).
    progress : show progress bars; figures : draw the report figures.
    """

    parts: tuple[str, ...] = ("likelihood", "coherence")
    seed: int = ranged(0, SEED)  # the top-level seed and n_test: prg.checks.TABLE's entries
    n_test: int | None = ranged(None, N_TEST)
    progress: bool = True
    figures: bool = True
    likelihood: LikelihoodSettings = field(default_factory=LikelihoodSettings)
    coherence: CoherenceSettings = field(default_factory=CoherenceSettings)
    classifier: ClassifierSettings = field(default_factory=ClassifierSettings)
    likeness: LikenessSettings = field(default_factory=LikenessSettings)
    styles: StyleSettings = field(default_factory=StyleSettings)
    kinematics: KinematicsSettings = field(default_factory=KinematicsSettings)

    def __post_init__(self) -> None:
        parts = list(self.parts)
        unknown = [p for p in parts if p not in PARTS]
        if unknown or not parts:
            raise SettingsError("parts", f"{parts}: choose from {list(PARTS)}")
        check_fields(self)
        object.__setattr__(self, "parts", tuple(parts))

    @property
    def classifiers_only(self) -> bool:
        return self.parts == ("classifiers",)
