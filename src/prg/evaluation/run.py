"""An evaluation of trained models: Table I log-likelihoods, cross-modal coherence and the
roughness of decoded letters, from checkpoints and a prepared test split.

:func:`load_models` and :func:`load_test_data` read the inputs, :func:`check_cells` refuses
Table I cells a model cannot estimate before any work starts, and the
parts an :class:`~prg.evaluation.settings.EvaluationSettings` asks for
(:func:`run_evaluation`) into an :class:`Evaluation` (rows as written to the CSV reports, and the flat metrics of
:func:`metrics_of`). The report texts are :func:`prg.evaluation.reports.report_texts`', the
figures :func:`prg.evaluation.figures.evaluation_figures`'; ``prg-evaluate``
(:mod:`prg.commands.evaluate`) reads the config, writes the files and logs the MLflow run.

Metric keys (``<model>/...``): Table I cells ``logp_T``, ``logp_T_given_S`` ... with trajectory
targets under a Gaussian of std ``likelihood.traj_std`` (default 1.0, the paper's scale), and
``logp_T_model_std``, ``logp_T_given_S_model_std`` ... under the model's own std, from the same
importance samples; coherence ``coherence_T_given_S`` (exact class) and
``coherence_folded_T_given_S`` (shape twins such as o/O/0 counted right), ``_sampled_`` for the
temperature-1 kind, ``_imputed_`` for MUSE's posterior mean after ``coherence.impute_steps``
rounds of imputing the missing modalities (``coherence_folded_imputed_T_given_S``); the second
classifier's ``coherence_second_T_given_S`` and ``coherence_folded_second_T_given_S``, and the
share of samples both classifiers read alike, ``agreement_T_given_S`` (same class) and
``agreement_folded_T_given_S`` (same shape-twin group), for generated trajectories and images
(:mod:`prg.evaluation.second_readers`; ``classifier/<reader>/test_accuracy`` for all four readers);
``roughness_ratio_T_given_S`` / ``_T_given_I`` (decoded letters' median roughness over the test
letters', whose median is ``test_split/roughness``; ``roughness_ratio_imputed_T_given_S`` ...).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import torch

from prg.alphabet import NUM_CLASSES
from prg.checks import FAMILIES
from prg.data.datamodule import check_model_shapes
from prg.data.store import load_split
from prg.errors import UsageError
from prg.evaluation.agreement import METRIC_SECOND_KEYS, SECOND_KEYS, agreement, second_metric_key
from prg.evaluation.classifiers import MODALITIES as CLASSIFIED
from prg.evaluation.classifiers import ensure_classifiers, load_classifier, predict
from prg.evaluation.coherence import (
    Posteriors,
    coherence_cells,
    folded_correct,
    generated_classes,
    generated_readings,
    generated_samples,
    per_class_rate,
    samples,
)
from prg.evaluation.handwriting import (
    kinematics_part,
    likeness_key,
    likeness_part,
    styles_part,
)
from prg.evaluation.likelihood import (
    MODEL_STD_SUFFIX,
    PAPER_TABLE1,
    TABLE1_CELLS,
    estimate_cell_multi,
)
from prg.evaluation.modes import LIKENESS_MEASURES
from prg.evaluation.second_readers import Reader, ensure_second_readers
from prg.evaluation.settings import IMPUTED, CoherenceSettings, EvaluationSettings
from prg.evaluation.smoothness import median_roughness
from prg.evaluation.styles import style_summary
from prg.models.base import MultimodalVAE
from prg.models.checkpoint import load_model
from prg.models.components import shift_images
from prg.models.likelihoods import Likelihoods
from prg.models.modalities import IMAGE, LABEL, LETTER, MODALITIES, NAMES, TRAJ, letters

log = logging.getLogger(__name__)

# Inputs from which decoded letters are scored for roughness: each single non-trajectory
# modality a model accepts (labels: cvae, avae_ts, muse; images: avae_ti, muse).
ROUGHNESS_INPUTS = tuple((m,) for m in NAMES if m != TRAJ)
TEST_ROUGHNESS_KEY = "test_split/roughness"


class LoadedModel(NamedTuple):
    """A model read from a checkpoint, the checkpoint's extra entries and its path."""

    model: MultimodalVAE
    info: dict[str, Any]
    path: Path


Models = Mapping[str, LoadedModel]
Data = dict[str, torch.Tensor]


@dataclass
class Evaluation:
    """What an evaluation produced (rows as written to the CSV reports)."""

    table1: list[dict] = field(default_factory=list)
    coherence: list[dict] = field(default_factory=list)
    smoothness: list[dict] = field(default_factory=list)
    shifted_images: list[dict] = field(default_factory=list)
    classifiers: dict[str, dict] = field(default_factory=dict)
    likeness: list[dict] = field(default_factory=list)
    kinematics: list[dict] = field(default_factory=list)
    styles: list[dict] = field(default_factory=list)
    metrics: dict[str, Any] = field(default_factory=dict)
    report_dir: Path | None = None
    # (model, target, given subset, kind) -> coherence per class, for the figures
    per_class: dict[tuple[str, str, str, str], np.ndarray] = field(default_factory=dict)
    # modality -> the first and second classifier (batch -> class ids), for the figures
    readers: dict[str, tuple] = field(default_factory=dict)


# ---- inputs ----------------------------------------------------------------------------------
def load_models(paths: Mapping[str, Path]) -> dict[str, LoadedModel]:
    """name -> the model of each checkpoint; a name that is a family must hold that family."""
    models = {}
    for name, path in paths.items():
        model, info = load_model(path)
        if name in FAMILIES and model.family != name:
            raise UsageError(f"checkpoint {path} holds a {model.family} model, not {name}")
        models[name] = LoadedModel(model, info, Path(path))
    return models


def load_test_data(root: Path) -> Data:
    """The whole test split of the prepared dataset folder ``root`` as model inputs."""
    arrays = load_split(root / "test.npz")
    check_model_shapes(arrays, root)
    if len(arrays[LABEL]) == 0:
        raise UsageError(f"dataset split {root / 'test.npz'} is empty: nothing to evaluate")
    return {m: MODALITIES[m].to_tensor(arrays[m]) for m in NAMES}


def subset(data: Data, n: int | None, seed: int) -> Data:
    """A seeded random subset of ``n`` samples (all when ``n`` is None or too large)."""
    total = samples(data)
    if n is None or n >= total:
        return data
    index = torch.from_numpy(np.sort(np.random.default_rng(seed).permutation(total)[:n]))
    return {m: v[index] for m, v in data.items()}


def _progress(items, desc: str, enabled: bool):
    if not enabled:
        return items
    from tqdm.auto import tqdm

    return tqdm(items, desc=desc)


# ---- the three parts -------------------------------------------------------------------------
def likelihood_jobs(models: Models, settings: EvaluationSettings) -> list[tuple[str, Any, str]]:
    """(name, model, cell) of each Table I cell to estimate: the requested cells each model
    supports; a cell named explicitly that a model cannot estimate raises, naming both."""
    cells, explicit = settings.likelihood.requested
    jobs = []
    for name, (model, _, _) in models.items():
        for cell in cells:
            target, given = TABLE1_CELLS[cell]
            if (target, given) in model.likelihood_cells:
                jobs.append((name, model, cell))
            elif explicit:
                model.check_cell(target, dict.fromkeys(given))  # raises, naming both
    return jobs


def check_cells(models: Models, settings: EvaluationSettings) -> None:
    """Refuse, before any work, a Table I cell named explicitly that a model cannot estimate."""
    if "likelihood" in settings.parts:
        likelihood_jobs(models, settings)


def likelihood_rows(models: Models, test: Data, settings: EvaluationSettings) -> list[dict]:
    """Table I rows: one per (model, cell) in the main table's convention, plus one per
    trajectory-target cell under the model's own std (cell ``<cell>_model_std``), both from one
    importance-sampling pass."""
    lk = settings.likelihood
    data = subset(test, lk.n_test, settings.seed)
    rows = []
    for name, model, cell in _progress(
        likelihood_jobs(models, settings), "Table I cells", settings.progress
    ):
        target, given = TABLE1_CELLS[cell]
        k = lk.k_conditional if given else lk.k_marginal
        own = model.likelihoods
        main = own if lk.traj_std is None else Likelihoods(traj_std=float(lk.traj_std))
        # trajectory targets: the main convention and the model's own std from the same samples
        conventions = [(cell, main, PAPER_TABLE1.get(model.family, {}).get(cell))]
        if target == TRAJ:
            conventions.append((f"{cell}{MODEL_STD_SUFFIX}", own, None))
        start = time.perf_counter()
        values = estimate_cell_multi(
            model,
            target,
            given,
            data,
            k,
            [lik for _, lik, _ in conventions],
            lk.batch_size,
            lk.chunk_rows,
            settings.seed,
            settings.progress,
        )
        seconds = round(time.perf_counter() - start, 2)
        for (key, lik, paper), v in zip(conventions, values, strict=True):
            rows.append(
                {
                    "model": name,
                    "family": model.family,
                    "cell": key,
                    "value": v.mean().item(),
                    "sem": (v.std() / math.sqrt(len(v))).item() if len(v) > 1 else 0.0,
                    "paper": paper,
                    "traj_std": lik.traj_std if target == TRAJ else None,
                    "k": k,
                    "n_test": len(v),
                    "seconds": seconds,
                }
            )
            log.info("%s %s = %.2f (K=%d)", name, key, rows[-1]["value"], k)
    return rows


def generation_kinds(
    model: MultimodalVAE, settings: CoherenceSettings
) -> list[tuple[str, float, int]]:
    """(kind, temperature, impute steps) of each way ``model``'s samples are generated: the
    configured temperatures, and ``imputed`` (posterior mean after ``impute_steps`` rounds of
    imputing the missing modalities, as the generation stage decodes) for families that
    impute."""
    kinds = [(kind, float(t), 0) for kind, t in settings.temperatures.items()]
    if model.imputes_missing and settings.impute_steps:
        kinds.append((IMPUTED, 0.0, int(settings.impute_steps)))
    return kinds


def shared_posteriors(models: Models, data: Data) -> dict[str, Posteriors]:
    """An empty :class:`~prg.evaluation.coherence.Posteriors` per model on ``data``."""
    return {name: Posteriors(model, data) for name, (model, _, _) in models.items()}


def coherence_rows(
    models: Models,
    classifiers: Mapping[str, Any],
    data: Data,
    settings: EvaluationSettings,
    second: Mapping[str, Reader] | None = None,
    posteriors: Mapping[str, Posteriors] | None = None,
) -> tuple[list[dict], dict]:
    """Rows per (model, target, subset, kind) on the test samples ``data``, and per-class rates
    for the figures. ``posteriors``: each model's :class:`~prg.evaluation.coherence.Posteriors`
    on ``data``, shared with :func:`roughness_rows` (None: computed here alone).

    ``coherence`` and ``coherence_folded`` are the first classifiers' (``classifiers``); with
    ``second`` readers (:func:`~prg.evaluation.second_readers.ensure_second_readers`) each row of
    a generated trajectory or image also holds the second reading and the agreement of the two
    (:func:`~prg.evaluation.agreement.agreement`); rows of generated labels hold None there.
    """
    if posteriors is None:
        posteriors = shared_posteriors(models, data)
    labels = data[LABEL]
    jobs = [
        (name, model, target, given, kind, temperature, steps)
        for name, (model, _, _) in models.items()
        for target, given in coherence_cells(model)
        for kind, temperature, steps in generation_kinds(model, settings.coherence)
    ]
    rows, per_class = [], {}
    for name, model, target, given, kind, temperature, steps in _progress(
        jobs, "coherence cells", settings.progress
    ):
        readers = []
        if target in classifiers:
            first = classifiers[target]
            readers.append(lambda x, first=first: predict(first, x))
            if second and target in second:
                readers.append(second[target].read)
        readings = generated_readings(
            model,
            target,
            given,
            data,
            readers,
            temperature,
            settings.coherence.batch_size,
            settings.seed,
            steps,
            posteriors[name],
        )
        predicted = readings[:, 0]
        correct = predicted == labels
        both = (
            agreement(predicted, readings[:, 1], labels)
            if readings.shape[1] > 1
            else dict.fromkeys(SECOND_KEYS)
        )
        rows.append(
            {
                "model": name,
                "family": model.family,
                "target": target,
                "given": letters(given, ","),
                "kind": kind,
                "temperature": temperature,
                "coherence": correct.float().mean().item(),
                "coherence_folded": folded_correct(predicted, labels).float().mean().item(),
                **both,
                "n": len(correct),
            }
        )
        per_class[(name, target, letters(given, ","), kind)] = per_class_rate(
            correct, labels, NUM_CLASSES
        ).numpy()
    return rows, per_class


def shifted_image_rows(
    models: Models, classifiers: Mapping[str, Any], data: Data, settings: EvaluationSettings
) -> list[dict]:
    """Coherence of what each model that takes an image alone generates from the test images
    ``data`` as they are (``shift`` 0) and moved off-centre by up to each of
    ``settings.coherence.image_shifts`` pixels per axis (one seeded random offset per image;
    posterior mean; the image's own reconstruction left out). A reader's letters are rarely
    centred to the pixel as the dataset renders them."""
    shifts = settings.coherence.image_shifts
    labels = data[LABEL]
    rows = []
    for name, (model, _, _) in models.items():
        if not shifts or (IMAGE,) not in model.accepted_inputs:
            continue
        for shift in (0, *shifts):
            generator = torch.Generator().manual_seed(settings.seed)
            moved = {IMAGE: shift_images(data[IMAGE], shift, generator)}
            for target in model.generated_modalities:
                if target == IMAGE:
                    continue
                predicted = generated_classes(
                    model,
                    target,
                    (IMAGE,),
                    moved,
                    classifiers,
                    0.0,
                    settings.coherence.batch_size,
                    settings.seed,
                )
                rows.append(
                    {
                        "model": name,
                        "family": model.family,
                        "target": target,
                        "given": LETTER[IMAGE],
                        "shift": shift,
                        "coherence": (predicted == labels).float().mean().item(),
                        "coherence_folded": folded_correct(predicted, labels).float().mean().item(),
                        "n": len(labels),
                    }
                )
    return rows


def roughness_rows(
    models: Models,
    data: Data,
    settings: EvaluationSettings,
    posteriors: Mapping[str, Posteriors] | None = None,
) -> list[dict]:
    """Roughness of the letters each model decodes (posterior mean) from labels and from images
    of the test samples ``data``, as a ratio to the roughness of their own letters
    (:mod:`prg.evaluation.smoothness`); ``posteriors`` as :func:`coherence_rows`."""
    if posteriors is None:
        posteriors = shared_posteriors(models, data)
    reference = median_roughness(data[TRAJ].numpy())
    rows = []
    for name, (model, _, _) in models.items():
        if TRAJ not in model.generated_modalities:
            continue
        means = [
            (k, steps) for k, t, steps in generation_kinds(model, settings.coherence) if t == 0
        ]
        for given in ROUGHNESS_INPUTS:
            if given not in model.accepted_inputs:
                continue
            for kind, steps in means:
                rows.append(
                    _roughness_row(
                        name, model, given, kind, steps, data, reference, settings, posteriors[name]
                    )
                )
    return rows


def _roughness_row(name, model, given, kind, steps, data, reference, settings, posteriors):
    decoded = generated_samples(
        model,
        TRAJ,
        given,
        data,
        0.0,
        settings.coherence.batch_size,
        settings.seed,
        steps,
        posteriors,
    ).numpy()
    median = median_roughness(decoded)
    row = {
        "model": name,
        "family": model.family,
        "target": TRAJ,
        "given": letters(given, ","),
        "kind": kind,
        "roughness": median,
        "reference": reference,
        "ratio": median / reference if reference > 0 else math.nan,
        "n": len(decoded),
    }
    log.info(
        "%s roughness T from %s (%s): %.3f (ratio %.2f)",
        name,
        letters(given, ","),
        kind,
        median,
        row["ratio"],
    )
    return row


def classifier_meta(folder: Path) -> dict[str, dict]:
    """Modality -> the meta (test accuracies ...) of each classifier saved in ``folder``."""
    return {m: load_classifier(folder / f"{m}.pt")[1] for m in CLASSIFIED}


# ---- metrics ---------------------------------------------------------------------------------
def _metric_key(row: dict, folded: bool = False) -> str:
    if "cell" in row:
        return row["cell"]
    target = LETTER[row["target"]]
    given = row["given"].replace(",", "")
    prefix = "coherence_folded" if folded else "coherence"
    if row["kind"] != "mean":
        prefix += f"_{row['kind']}"
    return f"{prefix}_{target}_given_{given}"


def _finite(value: float) -> bool:
    return value is not None and math.isfinite(value)


def metrics_of(result: Evaluation) -> dict[str, Any]:
    """Flat ``<model>/<metric>`` values for metrics.json and MLflow (non-finite roughness values
    are left out: they are shown as nan in coherence.md)."""
    metrics: dict[str, Any] = {}
    for row in result.table1:
        metrics[f"{row['model']}/{row['cell']}"] = round(row["value"], 4)
    for row in result.coherence:
        metrics[f"{row['model']}/{_metric_key(row)}"] = round(row["coherence"], 4)
        metrics[f"{row['model']}/{_metric_key(row, folded=True)}"] = round(
            row["coherence_folded"], 4
        )
        for key in METRIC_SECOND_KEYS:
            if row.get(key) is not None:
                metrics[f"{row['model']}/{second_metric_key(row, key)}"] = round(row[key], 4)
    for row in result.smoothness:
        kind = "" if row.get("kind", "mean") == "mean" else f"{row['kind']}_"
        given = row["given"].replace(",", "")
        key = f"roughness_ratio_{kind}{LETTER[row['target']]}_given_{given}"
        if _finite(row["ratio"]):
            metrics[f"{row['model']}/{key}"] = round(row["ratio"], 4)
    for row in result.shifted_images:
        cell = f"{LETTER[row['target']]}_given_{row['given']}_shift{row['shift']}"
        metrics[f"{row['model']}/coherence_{cell}"] = round(row["coherence"], 4)
        metrics[f"{row['model']}/coherence_folded_{cell}"] = round(row["coherence_folded"], 4)
    if result.smoothness and _finite(result.smoothness[0]["reference"]):
        metrics[TEST_ROUGHNESS_KEY] = round(result.smoothness[0]["reference"], 4)
    for modality, meta in result.classifiers.items():
        metrics[f"classifier/{modality}/test_accuracy"] = round(meta["test_accuracy"], 4)
    for row in result.likeness:
        mode = likeness_key(row["mode"])
        for measure in LIKENESS_MEASURES:
            if _finite(row[measure]):
                metrics[f"{row['family']}/likeness_{mode}_{measure}"] = round(row[measure], 4)
    for row in result.kinematics:
        group = row["group"].replace(": ", "_").replace(" ", "_").replace("(", "").replace(")", "")
        for measure in ("beta", "speed_cv", "lognormal_snr_db", "sparc", "peaks_per_s"):
            if _finite(row[measure]):
                metrics[f"kinematics/{group}_{measure}"] = round(row[measure], 4)
    for row in style_summary(result.styles):
        for key in ("generated", "ratio"):
            metrics[f"{row['family']}/style_k{row['k']}_{key}"] = round(row[key], 4)
        metrics[f"{row['family']}/style_real"] = round(row["real"], 4)
    return metrics


# ---- the whole evaluation --------------------------------------------------------------------
def run_evaluation(
    models: Models,
    test: Data,
    settings: EvaluationSettings,
    data_dir: Path,
    classifier_dir: Path,
) -> Evaluation:
    """Run the requested parts (likelihood, coherence with roughness) on ``models``.

    Parameters
    ----------
    models : name -> :class:`LoadedModel` (:func:`load_models`)
    test : the test split as model inputs (:func:`load_test_data`)
    settings : EvaluationSettings
    data_dir : the prepared dataset folder the classifiers are trained on
    classifier_dir : where the coherence classifiers are kept
        (:func:`~prg.evaluation.classifiers.ensure_classifiers`: reused while the data and their
        settings are unchanged)
    """
    result = Evaluation()
    if "likelihood" in settings.parts:
        result.table1 = likelihood_rows(models, test, settings)
    if {"coherence", "likeness"} & set(settings.parts):
        # both parts read with the same two classifiers per modality: loaded (or trained) once
        classifiers = ensure_classifiers(
            data_dir, classifier_dir, settings.classifier, progress=settings.progress
        )
        second = ensure_second_readers(
            data_dir, classifier_dir, classifiers, settings.classifier.seed
        )
    if "coherence" in settings.parts:
        result.classifiers = classifier_meta(classifier_dir)
        result.classifiers.update({r.name: r.meta for r in second.values()})
        # one seeded subset for every coherence part, so that they share each model's posteriors
        data = subset(test, settings.n_test, settings.seed)
        posteriors = shared_posteriors(models, data)
        result.coherence, result.per_class = coherence_rows(
            models, classifiers, data, settings, second, posteriors
        )
        result.readers = {
            m: (lambda x, first=classifiers[m]: predict(first, x), reader.read)
            for m, reader in second.items()
        }
        result.smoothness = roughness_rows(models, data, settings, posteriors)
        result.shifted_images = shifted_image_rows(models, classifiers, data, settings)
    if "likeness" in settings.parts:
        result.likeness = likeness_part(
            models, data_dir, classifiers[TRAJ], settings, second[TRAJ].read
        )
    if "styles" in settings.parts:
        result.styles = styles_part(models, data_dir, settings)
    if "kinematics" in settings.parts:
        result.kinematics = kinematics_part(models, settings)
    result.metrics = metrics_of(result)
    return result
