"""The parts of an evaluation that judge the models' writing against people's: the likeness of
their letters to held-out writers' (:mod:`prg.evaluation.modes`), writer identification of
letters written in held-out writers' styles (:mod:`prg.evaluation.styles`), and the pen's
kinematics beside human motion (:mod:`prg.evaluation.kinematics`). Each part returns the rows
of its report, or none (with a warning naming what is missing) when the data or the
checkpoints cannot support it. :func:`prg.evaluation.run.run_evaluation` calls them.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from prg.data.store import load_split
from prg.evaluation.settings import EvaluationSettings

if TYPE_CHECKING:
    from prg.evaluation.run import Models

log = logging.getLogger(__name__)


def likeness_key(mode: str) -> str:
    """A mode's name as a metric key part: ``hand (default)`` -> ``hand``, ``sampled T=0.5``
    -> ``sampled_t0.5``, ``val writers`` -> ``val_writers``."""
    return (
        mode.replace(" (default)", "").replace(" (paper)", "").replace("T=", "t").replace(" ", "_")
    )


def likeness_part(
    models: Models, data_dir: Path, classifier, settings: EvaluationSettings, shape_reader=None
):
    """The likeness table (:func:`prg.evaluation.modes.mode_rows`) of every model, legibility
    read by the trajectory ``classifier`` and by the second reader ``shape_reader``."""
    from prg.evaluation.modes import mode_rows

    names = {"val": "val writers", "train": "train originals"}
    test = load_split(data_dir / "test.npz")
    most = int(np.bincount(test["label"][~test["augmented"]]).max(initial=0))
    if most <= 3:  # the k-NN measures compare a class's letters with their 3 nearest
        log.warning(
            "likeness not computed: the test split has at most %d letters of a class (at least 4 "
            "are needed); prepare more writers",
            most,
        )
        return []
    references = {names[s]: load_split(data_dir / f"{s}.npz") for s in settings.likeness.references}
    loaded = {name: (m.model, m.info.get("hands")) for name, m in models.items()}
    return mode_rows(
        loaded,
        test,
        references,
        classifier,
        settings.likeness.n_per_class,
        settings.seed,
        progress=(lambda what: log.info("likeness: %s", what)) if settings.progress else None,
        shape_reader=shape_reader,
    )


def kinematics_part(models: Models, settings: EvaluationSettings) -> list[dict]:
    """The kinematics report's rows (:func:`prg.evaluation.kinematics.kinematics_rows`): the
    configured family's words, planned and executed, beside LASA and the controls."""
    from prg.evaluation.kinematics import kinematics_rows, medians

    k = settings.kinematics
    loaded = models.get(k.family)
    if loaded is None or loaded.info.get("hands") is None:
        log.warning("kinematics not computed: no %s checkpoint with hands evaluated", k.family)
        return []
    groups = kinematics_rows(
        loaded.model,
        loaded.info["hands"],
        k.words,
        robot=k.robot,
        progress=(lambda line: log.info("kinematics: %s", line)) if settings.progress else None,
    )
    return medians(groups)


def styles_part(models: Models, data_dir: Path, settings: EvaluationSettings) -> list[dict]:
    """Writer-identification rates of letters written in held-out writers' styles
    (:func:`prg.evaluation.styles.style_rates`), for every model whose checkpoint has hands."""
    from prg.evaluation.styles import style_rates

    test = load_split(data_dir / "test.npz")
    writers = len(set(test["writer"][~test["augmented"]]))
    if writers < 2:
        log.warning("styles not computed: the test split has %d writer (2 or more needed)", writers)
        return []
    rows = []
    for name, loaded in models.items():
        bank = loaded.info.get("hands")
        if bank is None:
            log.warning("%s: its checkpoint has no hands; no style rates", name)
            continue
        s = settings.styles
        for row in style_rates(loaded.model, bank, test, s.ks, s.seeds, s.n_eval, s.temperature):
            rows.append({"family": name, **row})
    return rows
