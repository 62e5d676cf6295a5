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
``evaluate`` run that holds the reports as artifacts.

Metric keys (``<model>/...``): Table I cells ``logp_T``, ``logp_T_given_S`` ... with trajectory
targets under a Gaussian of std ``likelihood.traj_std`` (default 1.0, the paper's scale), and
``logp_T_model_std``, ``logp_T_given_S_model_std`` ... under the model's own std, from the same
importance samples; coherence ``coherence_T_given_S`` (exact class) and
``coherence_folded_T_given_S`` (shape twins such as o/O/0 counted right), ``_sampled_`` for the
temperature-1 kind, ``_imputed_`` for MUSE's posterior mean after ``coherence.impute_steps``
rounds of imputing the missing modalities (``coherence_folded_imputed_T_given_S``);
``roughness_ratio_T_given_S`` / ``_T_given_I`` (decoded letters' median roughness over the test
letters', whose median is ``test_split/roughness``; ``roughness_ratio_imputed_T_given_S`` ...).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
from omegaconf import DictConfig, OmegaConf

from prg.checks import check_values
from prg.commands.cli import check_output, hydra_command
from prg.data.alphabet import ALPHABET, NUM_CLASSES
from prg.data.build import git_commit
from prg.data.datamodule import check_model_shapes
from prg.data.store import load_split
from prg.errors import UsageError
from prg.evaluation.classifiers import ensure_classifiers
from prg.evaluation.coherence import (
    coherence_cells,
    folded_correct,
    generated_classes,
    generated_samples,
    per_class_rate,
)
from prg.evaluation.likelihood import MODEL_STD_SUFFIX, TABLE1_CELLS, estimate_cell_multi
from prg.evaluation.reports import (
    PAPER_TABLE1,
    coherence_markdown,
    robustness_markdown,
    subset_name,
    table1_markdown,
    title,
    to_csv,
)
from prg.evaluation.smoothness import median_roughness
from prg.files import staged_outputs, write_json
from prg.models.base import LETTER, MultimodalVAE
from prg.models.checkpoint import load_model
from prg.models.likelihoods import Likelihoods

log = logging.getLogger(__name__)

PARTS = ("classifiers", "likelihood", "coherence")
FAMILIES = ("cvae", "avae_ts", "avae_ti", "muse")
TABLE1_COLUMNS = (
    "model",
    "family",
    "cell",
    "value",
    "sem",
    "paper",
    "traj_std",
    "k",
    "n_test",
    "seconds",
)
COHERENCE_COLUMNS = (
    "model",
    "family",
    "target",
    "given",
    "kind",
    "temperature",
    "coherence",
    "coherence_folded",
    "n",
)
# Inputs from which decoded letters are scored for roughness: each single non-trajectory
# modality a model accepts (labels: cvae, avae_ts, muse; images: avae_ti, muse).
ROUGHNESS_INPUTS = (("label",), ("image",))
# The generation kind of samples decoded after imputing the missing modalities (MUSE).
IMPUTED = "imputed"
TEST_ROUGHNESS_KEY = "test_split/roughness"


@dataclass
class Evaluation:
    """What an evaluation produced (rows as written to the CSV reports)."""

    table1: list[dict] = field(default_factory=list)
    coherence: list[dict] = field(default_factory=list)
    smoothness: list[dict] = field(default_factory=list)
    classifiers: dict[str, dict] = field(default_factory=dict)
    metrics: dict[str, Any] = field(default_factory=dict)
    report_dir: Path | None = None


# ---- inputs ----------------------------------------------------------------------------------
def _is_number(value: Any, integer: bool, minimum: float, strict: bool = False) -> bool:
    if isinstance(value, bool) or not isinstance(value, int if integer else int | float):
        return False
    return value > minimum if strict else value >= minimum


def _check_config(cfg: DictConfig) -> list[str]:
    parts = list(cfg.parts)
    unknown = [p for p in parts if p not in PARTS]
    if unknown or not parts:
        raise UsageError(f"parts {parts}: choose from {list(PARTS)}")
    lk = cfg.likelihood
    for key in ("k_marginal", "k_conditional", "batch_size", "chunk_rows"):
        if not _is_number(lk[key], integer=True, minimum=1):
            raise UsageError(f"likelihood.{key} must be an integer >= 1, got {lk[key]!r}")
    for key, value in (("n_test", cfg.n_test), ("likelihood.n_test", lk.n_test)):
        if value is not None and not _is_number(value, integer=True, minimum=1):
            raise UsageError(f"{key} must be null (all) or an integer >= 1, got {value!r}")
    if lk.traj_std is not None and not _is_number(lk.traj_std, False, 0, strict=True):
        raise UsageError(
            f"likelihood.traj_std must be null (each model's own) or > 0, got {lk.traj_std!r}"
        )
    for kind, value in cfg.coherence.temperatures.items():
        if not _is_number(value, integer=False, minimum=0):
            raise UsageError(f"coherence.temperatures.{kind} must be a number >= 0, got {value!r}")
    if IMPUTED in cfg.coherence.temperatures:
        raise UsageError(f"coherence.temperatures: {IMPUTED!r} names the imputed kind; rename it")
    steps = cfg.coherence.get("impute_steps", 0)
    if not _is_number(steps, integer=True, minimum=0):
        raise UsageError(f"coherence.impute_steps must be an integer >= 0, got {steps!r}")
    return parts


def _requested_cells(cfg: DictConfig) -> tuple[list[str], bool]:
    """Table I cells to estimate, and whether they were named explicitly (then every model must
    support every one)."""
    cells = cfg.likelihood.cells
    if cells == "all":
        return list(TABLE1_CELLS), False
    cells = [cells] if isinstance(cells, str) else list(cells)
    unknown = [c for c in cells if c not in TABLE1_CELLS]
    if unknown or not cells:
        raise UsageError(
            f"likelihood.cells {unknown or cells}: use 'all' or a list of {list(TABLE1_CELLS)}"
        )
    return cells, True


def _checkpoint_paths(cfg: DictConfig) -> dict[str, Path]:
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


def load_models(cfg: DictConfig) -> dict[str, tuple[MultimodalVAE, dict[str, Any], Path]]:
    """name -> (model, checkpoint info, path); a name that is a family must hold that family."""
    models = {}
    for name, path in _checkpoint_paths(cfg).items():
        model, info = load_model(path)
        if name in FAMILIES and model.family != name:
            raise UsageError(f"checkpoint {path} holds a {model.family} model, not {name}")
        models[name] = (model, info, path)
    return models


def _test_data(cfg: DictConfig) -> dict[str, torch.Tensor]:
    """The whole test split as model inputs."""
    root = Path(cfg.paths.data_dir) / "prepared" / cfg.data.name
    arrays = load_split(root / "test.npz")
    check_model_shapes(arrays, root)
    if len(arrays["label"]) == 0:
        raise UsageError(f"dataset split {root / 'test.npz'} is empty: nothing to evaluate")
    return {
        "traj": torch.from_numpy(arrays["traj"]).float(),
        "label": torch.from_numpy(arrays["label"].astype(np.int64)),
        "image": torch.from_numpy(arrays["image"]).float().div(255.0).unsqueeze(1),
    }


def _subset(data: dict[str, torch.Tensor], n: int | None, seed: int) -> dict[str, torch.Tensor]:
    """A seeded random subset of ``n`` samples (all when ``n`` is None or too large)."""
    total = len(data["label"])
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
def likelihood_rows(models, test: dict[str, torch.Tensor], cfg: DictConfig) -> list[dict]:
    """Table I rows: one per (model, cell) in the main table's convention, plus one per
    trajectory-target cell under the model's own std (cell ``<cell>_model_std``), both from one
    importance-sampling pass."""
    cells, explicit = _requested_cells(cfg)
    lk = cfg.likelihood
    data = _subset(test, lk.n_test, cfg.seed)
    jobs = []
    for name, (model, _, _) in models.items():
        for cell in cells:
            target, given = TABLE1_CELLS[cell]
            if (target, given) in model.likelihood_cells:
                jobs.append((name, model, cell))
            elif explicit:
                model.check_cell(target, {m: data[m] for m in given})  # raises, naming both
    rows = []
    for name, model, cell in _progress(jobs, "Table I cells", cfg.progress):
        target, given = TABLE1_CELLS[cell]
        k = lk.k_conditional if given else lk.k_marginal
        own = model.likelihoods
        main = own if lk.traj_std is None else Likelihoods(traj_std=float(lk.traj_std))
        # trajectory targets: the main convention and the model's own std from the same samples
        conventions = [(cell, main, PAPER_TABLE1.get(model.family, {}).get(cell))]
        if target == "traj":
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
            cfg.seed,
            cfg.progress,
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
                    "traj_std": lik.traj_std if target == "traj" else None,
                    "k": k,
                    "n_test": len(v),
                    "seconds": seconds,
                }
            )
            log.info("%s %s = %.2f (K=%d)", name, key, rows[-1]["value"], k)
    return rows


def generation_kinds(model, cfg: DictConfig) -> list[tuple[str, float, int]]:
    """(kind, temperature, impute steps) of each way ``model``'s samples are generated: the
    configured temperatures, and ``imputed`` (posterior mean after ``coherence.impute_steps``
    rounds of imputing the missing modalities, as the generation stage decodes) for families
    that impute."""
    kinds = [(kind, float(t), 0) for kind, t in cfg.coherence.temperatures.items()]
    steps = cfg.coherence.get("impute_steps", 0)
    if model.imputes_missing and steps:
        kinds.append((IMPUTED, 0.0, int(steps)))
    return kinds


def coherence_rows(
    models, classifiers, test: dict[str, torch.Tensor], cfg: DictConfig
) -> tuple[list[dict], dict]:
    """Rows per (model, target, subset, kind), and per-class rates for the figures."""
    data = _subset(test, cfg.n_test, cfg.seed)
    jobs = [
        (name, model, target, given, kind, temperature, steps)
        for name, (model, _, _) in models.items()
        for target, given in coherence_cells(model)
        for kind, temperature, steps in generation_kinds(model, cfg)
    ]
    rows, per_class = [], {}
    for name, model, target, given, kind, temperature, steps in _progress(
        jobs, "coherence cells", cfg.progress
    ):
        predicted = generated_classes(
            model,
            target,
            given,
            data,
            classifiers,
            temperature,
            cfg.coherence.batch_size,
            cfg.seed,
            steps,
        )
        correct = predicted == data["label"]
        rows.append(
            {
                "model": name,
                "family": model.family,
                "target": target,
                "given": subset_name(given),
                "kind": kind,
                "temperature": temperature,
                "coherence": correct.float().mean().item(),
                "coherence_folded": folded_correct(predicted, data["label"]).float().mean().item(),
                "n": len(correct),
            }
        )
        per_class[(name, target, subset_name(given), kind)] = per_class_rate(
            correct, data["label"], NUM_CLASSES
        ).numpy()
    return rows, per_class


def roughness_rows(models, test: dict[str, torch.Tensor], cfg: DictConfig) -> list[dict]:
    """Roughness of the letters each model decodes (posterior mean) from labels and from images,
    as a ratio to the roughness of the same test samples' letters
    (:mod:`prg.evaluation.smoothness`)."""
    data = _subset(test, cfg.n_test, cfg.seed)
    reference = median_roughness(data["traj"].numpy())
    rows = []
    for name, (model, _, _) in models.items():
        if "traj" not in model.generated_modalities:
            continue
        means = [(k, steps) for k, t, steps in generation_kinds(model, cfg) if t == 0]
        for given in ROUGHNESS_INPUTS:
            if given not in model.accepted_inputs:
                continue
            for kind, steps in means:
                rows.append(_roughness_row(name, model, given, kind, steps, data, reference, cfg))
    return rows


def _roughness_row(name, model, given, kind, steps, data, reference, cfg) -> dict:
    decoded = generated_samples(
        model, "traj", given, data, 0.0, cfg.coherence.batch_size, cfg.seed, steps
    ).numpy()
    median = median_roughness(decoded)
    row = {
        "model": name,
        "family": model.family,
        "target": "traj",
        "given": subset_name(given),
        "kind": kind,
        "roughness": median,
        "reference": reference,
        "ratio": median / reference if reference > 0 else math.nan,
        "n": len(decoded),
    }
    log.info(
        "%s roughness T from %s (%s): %.3f (ratio %.2f)",
        name,
        subset_name(given),
        kind,
        median,
        row["ratio"],
    )
    return row


# ---- outputs ---------------------------------------------------------------------------------
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
    for row in result.smoothness:
        kind = "" if row.get("kind", "mean") == "mean" else f"{row['kind']}_"
        given = row["given"].replace(",", "")
        key = f"roughness_ratio_{kind}{LETTER[row['target']]}_given_{given}"
        if _finite(row["ratio"]):
            metrics[f"{row['model']}/{key}"] = round(row["ratio"], 4)
    if result.smoothness and _finite(result.smoothness[0]["reference"]):
        metrics[TEST_ROUGHNESS_KEY] = round(result.smoothness[0]["reference"], 4)
    for modality, meta in result.classifiers.items():
        metrics[f"classifier/{modality}/test_accuracy"] = round(meta["test_accuracy"], 4)
    return metrics


def _figures(models, per_class, data: dict[str, torch.Tensor], folder: Path) -> None:
    from prg.plotting import pyplot
    from prg.training.generation_figures import image_grid, trajectory_grid

    plt = pyplot()
    first = [
        int(np.flatnonzero(data["label"].numpy() == c)[0])
        for c in range(NUM_CLASSES)
        if (data["label"] == c).any()
    ]
    index = torch.tensor(first)
    names = [ALPHABET[int(c)] for c in data["label"][index]]
    for name, (model, _, _) in models.items():
        for target, given in coherence_cells(model):
            if target == "label" or target in given:
                continue
            out = model.generate({m: data[m][index] for m in given}, target)[0].numpy()
            draw = trajectory_grid if target == "traj" else image_grid
            label = f"{LETTER[target]}_given_{''.join(LETTER[m] for m in given)}"
            fig = draw(
                out, names, title=f"{name}: {label} (posterior mean), one test sample per class"
            )
            fig.savefig(folder / f"{name}_{label}.png", dpi=110)
            plt.close(fig)
        keys = [k for k in per_class if k[0] == name and k[3] == "mean"]
        if keys:
            matrix = np.stack([per_class[k] for k in keys])
            fig, ax = plt.subplots(figsize=(14, 0.35 * len(keys) + 1.2))
            ax.imshow(matrix, vmin=0, vmax=1, cmap="viridis", aspect="auto")
            ax.set_yticks(
                range(len(keys)), [f"{LETTER[k[1]]} | {{{k[2]}}}" for k in keys], fontsize=7
            )
            ax.set_xticks(range(NUM_CLASSES), list(ALPHABET), fontsize=6)
            ax.set_title(f"{name}: coherence per class (posterior mean generation)", fontsize=9)
            fig.colorbar(ax.images[0], ax=ax, fraction=0.02)
            fig.tight_layout()
            fig.savefig(folder / f"{name}_coherence_per_class.png", dpi=110)
            plt.close(fig)


def _setup_line(cfg: DictConfig, models, part: str) -> str:
    lk = cfg.likelihood
    ckpts = ", ".join(f"{n}: {p}" for n, (_, _, p) in models.items())
    if part == "likelihood":
        n = lk.n_test if lk.n_test is not None else "all"
        std = "each model's own" if lk.traj_std is None else f"{lk.traj_std:g}"
        what = (
            f"K = {lk.k_marginal} (marginals) / {lk.k_conditional} (conditionals), "
            f"test samples: {n}, trajectory std: {std} (second table: each model's own)"
        )
    else:
        what = f"test samples: {cfg.n_test if cfg.n_test is not None else 'all'}"
    return f"Data: {cfg.data.name} test split; {what}; seed {cfg.seed}. Checkpoints: {ckpts}."


def write_reports(result: Evaluation, models, per_class, data, cfg: DictConfig, parts) -> Path:
    """Write every report through a staging folder into ``report_dir``."""
    report_dir = Path(cfg.report_dir)
    with staged_outputs(report_dir) as staging:
        if "likelihood" in parts:
            (staging / "table1.csv").write_text(to_csv(result.table1, TABLE1_COLUMNS))
            (staging / "table1.md").write_text(
                table1_markdown(
                    result.table1, _setup_line(cfg, models, "likelihood"), cfg.likelihood.traj_std
                )
            )
        if "coherence" in parts:
            setup = _setup_line(cfg, models, "coherence")
            (staging / "coherence.csv").write_text(to_csv(result.coherence, COHERENCE_COLUMNS))
            (staging / "coherence.md").write_text(
                coherence_markdown(result.coherence, result.classifiers, setup, result.smoothness)
            )
            kind = next(iter(cfg.coherence.temperatures))
            (staging / "robustness.md").write_text(
                robustness_markdown(result.coherence, kind, setup)
            )
            if cfg.figures:
                (staging / "figures").mkdir()
                _figures(models, per_class, data, staging / "figures")
        write_json(staging / "metrics.json", result.metrics)
    return report_dir


def log_to_mlflow(result: Evaluation, models, cfg: DictConfig) -> str:
    """Metrics into each model's training run (if in this store) and one ``evaluate`` run with
    the reports as artifacts; returns the evaluate run's id."""
    from mlflow.exceptions import MlflowException

    from prg.tracking import task_client

    client, experiment = task_client(cfg)
    now = int(time.time() * 1000)
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
            run_id = client.create_run(
                experiment, run_name=f"{name}-evaluate", tags={"prg.family": model.family}
            ).info.run_id
            client.set_terminated(run_id)
        for key, value in metrics.items():
            client.log_metric(run_id, f"test/{key}", value, timestamp=now)
        client.set_tag(run_id, "prg.evaluated_checkpoint", str(path))
    run = client.create_run(
        experiment,
        run_name=cfg.run_name,
        tags={
            "prg.task": "evaluate",
            "prg.git_commit": git_commit(),
            "prg.data.name": cfg.data.name,
        },
    )
    run_id = run.info.run_id
    for key, value in result.metrics.items():
        client.log_metric(run_id, f"test/{key}", value, timestamp=now)
    client.log_text(run_id, OmegaConf.to_yaml(cfg, resolve=True), "config/config.yaml")
    client.log_artifacts(run_id, str(result.report_dir), "reports")
    client.set_terminated(run_id)
    return run_id


def evaluate(cfg: DictConfig) -> Evaluation:
    """Task: run the requested parts on the configured checkpoints and write the reports."""
    check_values(cfg)
    parts = _check_config(cfg)
    _requested_cells(cfg)
    result = Evaluation()
    data_dir = Path(cfg.paths.data_dir) / "prepared" / cfg.data.name
    classifier_cfg = OmegaConf.to_container(cfg.classifier, resolve=True)
    classifier_dir = Path(classifier_cfg.pop("dir"))
    if parts == ["classifiers"]:
        check_output(classifier_dir, "classifier.dir")
    else:
        check_output(cfg.report_dir, "report_dir")
    if parts == ["classifiers"]:
        ensure_classifiers(data_dir, classifier_dir, classifier_cfg, progress=cfg.progress)
        return result
    models = load_models(cfg)
    test = _test_data(cfg)
    if "likelihood" in parts:
        result.table1 = likelihood_rows(models, test, cfg)
    per_class = {}
    if "coherence" in parts:
        classifiers = ensure_classifiers(
            data_dir, classifier_dir, classifier_cfg, progress=cfg.progress
        )
        result.classifiers = _classifier_meta(classifier_dir)
        result.coherence, per_class = coherence_rows(models, classifiers, test, cfg)
        result.smoothness = roughness_rows(models, test, cfg)
    result.metrics = metrics_of(result)
    result.report_dir = write_reports(result, models, per_class, test, cfg, parts)
    log_to_mlflow(result, models, cfg)
    log.info("reports in %s", result.report_dir)
    for name, (model, _, _) in models.items():
        log.info("%s: %s", name, title(model.family))
    return result


def _classifier_meta(folder: Path) -> dict[str, dict]:
    from prg.evaluation.classifiers import load_classifier

    return {m: load_classifier(folder / f"{m}.pt")[1] for m in ("traj", "image")}


main = hydra_command(evaluate, "evaluate", "prg-evaluate")

if __name__ == "__main__":
    main()
