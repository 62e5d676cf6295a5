"""Settings of an evaluation (``conf/evaluate.yaml``), each class checking its own fields.

A refused value raises :class:`~prg.errors.SettingsError` naming the field (``k_marginal``); the
command layer (:mod:`prg.commands.evaluate`) adds the config path (``likelihood.k_marginal``).
The numeric fields' ranges are tables of :mod:`prg.checks` (``LIKELIHOOD_RANGES`` ...), which
also checks the config options with them.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from prg.checks import (
    CLASSIFIER_RANGES,
    COHERENCE_RANGES,
    EVALUATION_RANGES,
    IMAGE_SHIFT,
    LIKELIHOOD_RANGES,
    LIKENESS_RANGES,
    STYLE_RANGES,
    TEMPERATURE,
    require_number,
)
from prg.errors import SettingsError
from prg.evaluation.classifiers import DEFAULT_CFG
from prg.evaluation.likelihood import PAPER_TRAJ_STD, TABLE1_CELLS
from prg.fields import check_ranges

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
    k_marginal: int = 1000
    k_conditional: int = 5000
    n_test: int | None = None
    batch_size: int = 64
    chunk_rows: int = 4096
    traj_std: float | None = PAPER_TRAJ_STD

    def __post_init__(self) -> None:
        check_ranges(self, LIKELIHOOD_RANGES)
        if self.cells != "all":
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
            return list(TABLE1_CELLS), False
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
    impute_steps: int = 0
    batch_size: int = 512
    image_shifts: tuple[int, ...] = (1, 2)

    def __post_init__(self) -> None:
        spec = TEMPERATURE
        for kind, value in self.temperatures.items():
            require_number(value, f"temperatures.{kind}", spec)
        if IMPUTED in self.temperatures:
            # "temperatures:" keeps the message users know: "coherence.temperatures: 'imputed' ..."
            raise SettingsError("temperatures:", f"{IMPUTED!r} names the imputed kind; rename it")
        check_ranges(self, COHERENCE_RANGES)
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

    n_per_class: int = 10
    references: tuple[str, ...] = ("val", "train")

    def __post_init__(self) -> None:
        check_ranges(self, LIKENESS_RANGES)
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
    n_eval: int = 12
    temperature: float = 0.5

    def __post_init__(self) -> None:
        check_ranges(self, STYLE_RANGES)
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

    epochs: int = DEFAULT_CFG["epochs"]
    batch_size: int = DEFAULT_CFG["batch_size"]
    lr: float = DEFAULT_CFG["lr"]
    seed: int = DEFAULT_CFG["seed"]

    def __post_init__(self) -> None:
        check_ranges(self, CLASSIFIER_RANGES)


@dataclass(frozen=True)
class EvaluationSettings:
    """What ``prg-evaluate`` runs (the top level of ``conf/evaluate.yaml``).

    parts : some of :data:`PARTS`; ``classifiers`` alone only trains the classifiers.
    seed : seeds the test subsets, the importance samples and the generated samples.
    n_test : test samples for coherence and roughness (None: all; else a seeded subset).
    progress : show progress bars; figures : draw the report figures.
    """

    parts: tuple[str, ...] = ("likelihood", "coherence")
    seed: int = 0
    n_test: int | None = None
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
        check_ranges(self, EVALUATION_RANGES)
        object.__setattr__(self, "parts", tuple(parts))

    @property
    def classifiers_only(self) -> bool:
        return self.parts == ("classifiers",)
