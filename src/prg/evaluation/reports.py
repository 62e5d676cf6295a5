"""Report tables of an evaluation: Table I (with the paper's values), coherence (exact and with
shape twins folded), smoothness of decoded letters, robustness.

Pure functions from result rows (lists of dicts) to CSV/Markdown text; :func:`report_texts`
gives every report file of an :class:`~prg.evaluation.run.Evaluation`; the caller writes them.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from prg.evaluation.agreement import agreement_markdown, mark, mark_note
from prg.evaluation.classifiers import SHAPE_TWINS
from prg.evaluation.likelihood import (
    MODEL_STD_SUFFIX,
    PAPER_TABLE1,
    PAPER_TRAJ_STD,
    TABLE1_CELLS,
    density_convention,
)
from prg.evaluation.modes import LIKENESS_MEASURES
from prg.evaluation.styles import style_summary
from prg.models.modalities import LABEL, LETTER, NAMES, TRAJ, letters

if TYPE_CHECKING:
    from prg.evaluation.run import Evaluation
    from prg.evaluation.settings import EvaluationSettings

FAMILY_TITLES = {
    "cvae": "PRG_CVAE(T,S)",
    "avae_ts": "PRG_AVAE(T,S)",
    "avae_ti": "PRG_AVAE(T,I)",
    "muse": "PRG_MUSE(T,S,I)",
    "mvae": "MVAE(T,S,I)",
    "mmvae": "MMVAE(T,S,I)",
    "mopoe": "MoPoE(T,S,I)",
}


PAPER_NOTE = (
    "Paper values (in parentheses) come from models trained on the augmented UJI Char Pen 2 "
    "data with the authors' density convention, which the paper does not state. Their "
    "trajectory cells are on the scale of a unit-variance Gaussian with its normalising constant "
    "(-200 log sqrt(2 pi) = -183.8 nats, minus half the squared error), the reference code's "
    "implicit choice, so the main table uses it and its trajectory columns compare like with "
    "like. Under unit variance the squared error weighs 100 times less than under "
    "the std 0.1 the models were trained with, so differences between models shrink; the "
    "second table keeps the models' own std, whose constant of +276.7 nats makes most values "
    "positive. Their positive log p(x_S | x_T) (1.94, 1.96) is impossible for a normalised "
    "categorical - a probability is at most 1, its log at most 0 - so their label terms, and "
    "likely their image terms, were scored with another convention (a continuous density on "
    "one-hot labels, for instance, can exceed 1) and differ from ours by constants: in those "
    "columns compare orderings between families, not absolute numbers. Our data may also "
    "differ (synthetic substitute unless data=uji)."
)

FOLDED_NOTE = (
    "Folded: a generated sample whose class is a shape twin of the true class ("
    + ", ".join("/".join(group) for group in SHAPE_TWINS)
    + ": the same shape once size and position are normalised away, `SHAPE_TWINS` in "
    "prg/evaluation/classifiers.py) also counts as coherent, the way the classifiers' own "
    "folded accuracy is judged."
)

ROUGHNESS_DEFINITION = (
    "Roughness of a letter: the sum of |p[i+1] - 2 p[i] + p[i-1]| over its 100 points divided "
    "by its arc length, the sum of |p[i+1] - p[i]| (`prg/evaluation/smoothness.py`). It is "
    "scale-free, 0 for a straight stroke, and grows with point-to-point jitter long before the "
    "letter's class changes. Letters are decoded (posterior mean) from each test sample's label "
    "or image; the ratio is their median roughness over the median roughness of the same test "
    "samples' letters (1: as smooth as the data)."
)


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
    "coherence_second",
    "coherence_folded_second",
    "agreement",
    "agreement_folded",
    "difference",
    "difference_folded",
    "coherence_folded_both",
    "n",
)


ONE_SEED = (
    "One seed: each model trained once, so no spread over training seeds is shown "
    "(`make baselines`: mean and 95 % CI over seeds)."
)


def title(family: str) -> str:
    return FAMILY_TITLES.get(family, family)


def subset_name(given: Sequence[str]) -> str:
    """('label', 'image') -> 'S,I' (the paper's letters, in T, S, I order)."""
    return letters(given, ",")


def to_csv(rows: list[dict], columns: Sequence[str]) -> str:
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(columns), extrasaction="ignore")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: _csv_value(row.get(k)) for k in columns})
    return buffer.getvalue()


def _csv_value(value):
    if isinstance(value, float):
        return "" if math.isnan(value) else f"{value:.6g}"
    return "" if value is None else value


def _md_table(header: list[str], body: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(row) + " |" for row in body]
    return "\n".join(lines)


def _estimate(row: dict | None) -> str:
    return "-" if row is None else f"{row['value']:.2f} ± {row['sem']:.2f}"


def _row_title(name: str, family: str) -> str:
    return title(family) if name == family else f"{name}: {title(family)}"


def table1_markdown(rows: list[dict], setup: str, traj_std: float | None = PAPER_TRAJ_STD) -> str:
    """Wide Table I: one row per evaluated model, one column per cell, ``ours (paper)``, with
    trajectory targets under a Gaussian of std ``traj_std`` (None: each model's own); below it,
    the trajectory cells under each model's own std (rows ``<cell>_model_std``)."""
    names = list(dict.fromkeys(r["model"] for r in rows))
    families = {r["model"]: r["family"] for r in rows}
    by_key = {(r["model"], r["cell"]): r for r in rows}
    header = ["model", *[_cell_title(c) for c in TABLE1_CELLS]]
    body = []
    for name in names:
        family = families[name]
        cells = []
        for cell in TABLE1_CELLS:
            text = _estimate(by_key.get((name, cell)))
            paper = PAPER_TABLE1.get(family, {}).get(cell)
            if paper is not None:
                text += f" ({paper:.2f})"
            cells.append(text)
        body.append([_row_title(name, family), *cells])
    main_std = "each model's own std" if traj_std is None else f"std {traj_std:g}"
    parts = [
        "# Table I: importance-weighted log-likelihoods (higher is better)",
        setup,
        f"Trajectory targets under a Gaussian with {main_std} per coordinate"
        + (" (unit variance: the paper's scale)" if traj_std == 1.0 else "")
        + "; the paper's values in parentheses.",
        _md_table(header, body),
    ]
    traj_cells = [c for c, (target, _) in TABLE1_CELLS.items() if target == TRAJ]
    own = [
        [
            _row_title(name, families[name]),
            f"{std:g}" if (std := _own_std(rows, name)) is not None else "-",
            *[_estimate(by_key.get((name, c + MODEL_STD_SUFFIX))) for c in traj_cells],
        ]
        for name in names
        if any((name, c + MODEL_STD_SUFFIX) in by_key for c in traj_cells)
    ]
    if own:
        parts += [
            "## Trajectory cells under each model's own std",
            "The same importance samples, with the trajectory Gaussian's std the model was "
            "trained with (`traj_std`; metric keys `<cell>_model_std`). No paper values: the "
            "paper's are on the unit-variance scale of the table above.",
            _md_table(["model", "std", *[_cell_title(c) for c in traj_cells]], own),
        ]
    parts += [f"Density convention: {density_convention(traj_std)}", PAPER_NOTE]
    return "\n\n".join(parts) + "\n"


def _own_std(rows: list[dict], name: str) -> float | None:
    stds = {
        r["traj_std"]
        for r in rows
        if r["model"] == name and r["cell"].endswith(MODEL_STD_SUFFIX) and "traj_std" in r
    }
    return stds.pop() if len(stds) == 1 else None


def _cell_title(cell: str) -> str:
    target, given = TABLE1_CELLS[cell]
    inner = f"x_{LETTER[target]}" + (f" \\| x_{subset_name(given)}" if given else "")
    return f"log p({inner})"


def _rate(row: dict | None, key: str) -> str:
    return "-" if row is None or row.get(key) is None else f"{row[key]:.3f}"


def coherence_markdown(
    rows: list[dict], classifier_info: dict, setup: str, smoothness: list[dict] | None = None
) -> str:
    """Per model: a row per (target, input subset), exact and folded columns per generation
    kind (the first classifiers'); then the two classifiers' agreement
    (:func:`agreement_markdown`) and the roughness of decoded letters (``smoothness`` rows),
    when given."""
    kinds = list(dict.fromkeys(r["kind"] for r in rows))
    parts = [
        "# Cross-modal coherence",
        setup,
        "Fraction of generated samples that the first independent classifier assigns to the "
        "conditioning class (labels: the decoded label's accuracy). Reconstruction cells "
        "(target among the inputs) are marked with *. " + FOLDED_NOTE + mark_note(rows),
        _classifier_lines(classifier_info),
    ]
    header = ["generated", *[h for k in kinds for h in (k, f"{k}, folded")]]
    for name in dict.fromkeys(r["model"] for r in rows):
        mine = [r for r in rows if r["model"] == name]
        family = mine[0]["family"]
        cells = list(dict.fromkeys((r["target"], r["given"]) for r in mine))
        by_key = {(r["target"], r["given"], r["kind"]): r for r in mine}
        body = []
        for target, given in cells:
            star = "*" if LETTER[target] in given.split(",") else ""
            body.append(
                [f"{LETTER[target]} given {{{given}}}{star}"]
                + [
                    _rate(by_key.get((target, given, k)), key)
                    + mark(by_key.get((target, given, k)), key)
                    for k in kinds
                    for key in ("coherence", "coherence_folded")
                ]
            )
        parts += [f"## {name}: {title(family)}", _md_table(header, body)]
    parts += agreement_markdown(rows, title, _md_table)
    if smoothness:
        parts += smoothness_markdown(smoothness)
    return "\n\n".join(parts) + "\n"


def smoothness_markdown(rows: list[dict]) -> list[str]:
    """The smoothness section of coherence.md (its paragraphs)."""
    body = [
        [
            _row_title(r["model"], r["family"]),
            f"{LETTER[r['target']]} given {{{r['given']}}}"
            + ("" if r.get("kind", "mean") == "mean" else f" ({r['kind']})"),
            f"{r['roughness']:.3f}",
            f"{r['ratio']:.2f}",
        ]
        for r in rows
    ]
    return [
        "## Smoothness of decoded letters",
        ROUGHNESS_DEFINITION + f" Median roughness of the test letters: {rows[0]['reference']:.3f} "
        f"({rows[0]['n']} samples).",
        _md_table(["model", "generated", "median roughness", "ratio to test letters"], body),
    ]


FIRST_READERS = {"traj": "first: MLP on the coordinates", "image": "first: CNN on the pixels"}


def _classifier_lines(info: dict) -> str:
    lines = [
        "Classifiers (trained on the training split, scored on the real test split, i.e. on "
        "held-out writers):"
    ]
    for name, meta in info.items():
        reader = meta.get("reader", FIRST_READERS.get(name))
        reader = f" ({reader})" if reader else ""
        lines.append(
            f"- {name}{reader}: test accuracy {meta['test_accuracy']:.3f}"
            + (
                f" (case twins folded: {meta['test_folded_accuracy']:.3f})"
                if "test_folded_accuracy" in meta
                else ""
            )
        )
    return "\n".join(lines)


_LETTERS = [LETTER[m] for m in NAMES]  # T, S, I


def _subset_order(subset: str) -> tuple:
    """Cross-modal subsets first, then those holding T; smaller first; T, S, I order."""
    given = subset.split(",")
    return (LETTER[TRAJ] in given, len(given), [_LETTERS.index(c) for c in given])


def robustness_markdown(
    rows: list[dict], kind: str, setup: str, shifted: list[dict] | None = None
) -> str:
    """Trajectory coherence for every input subset each model accepts (missing modalities),
    then, with ``shifted`` rows (:func:`~prg.evaluation.run.shifted_image_rows`), coherence
    from images moved off-centre."""
    traj = [r for r in rows if r["target"] == TRAJ and r["kind"] == kind]
    subsets = sorted(dict.fromkeys(r["given"] for r in traj), key=_subset_order)
    value = {(r["model"], r["given"]): r for r in traj}
    body = []
    for name in dict.fromkeys(r["model"] for r in traj):
        family = next(r["family"] for r in traj if r["model"] == name)
        body.append(
            [title(family) if name == family else name]
            + [_exact_folded(value.get((name, s))) for s in subsets]
        )
    header = [
        "model",
        *[f"{{{s}}}" + ("*" if LETTER[TRAJ] in s.split(",") else "") for s in subsets],
    ]
    return (
        "\n\n".join(
            [
                "# Missing-modality robustness: coherence of generated trajectories",
                setup,
                f"Each column is the subset of inputs given ({kind} generation); '-' where the model "
                "cannot take that subset. * marks subsets that contain the trajectory itself "
                "(reconstruction). Exact coherence, folded in parentheses. " + FOLDED_NOTE,
                _md_table(header, body),
                *_shifted_section(shifted or []),
            ]
        )
        + "\n"
    )


def _shifted_section(rows: list[dict]) -> list[str]:
    """The robustness report's table of coherence from images moved off-centre (none without
    rows)."""
    if not rows:
        return []
    shifts = sorted({r["shift"] for r in rows})
    value = {(r["model"], r["target"], r["shift"]): r for r in rows}
    body = []
    for name, target in dict.fromkeys((r["model"], r["target"]) for r in rows):
        family = next(r["family"] for r in rows if r["model"] == name)
        body.append(
            [title(family) if name == family else name, f"{LETTER[target]} from {{I}}"]
            + [_exact_folded(value.get((name, target, s))) for s in shifts]
        )
    header = ["model", "generated", *[f"moved <= {s} px" if s else "as is" for s in shifts]]
    return [
        "## Images moved off-centre",
        "Each test image moved by its own random whole-pixel offset of up to the column's "
        "pixels along each axis (seeded; the background fills the uncovered border), then "
        "the trajectory or label generated from it alone (posterior mean). The dataset renders "
        "every letter centred; a reader's images are rarely centred to the pixel. Exact "
        "coherence, folded in parentheses.",
        _md_table(header, body),
    ]


def _exact_folded(row: dict | None) -> str:
    if row is None:
        return "-"
    if row.get("coherence_folded") is None:
        return f"{row['coherence']:.3f}"
    return f"{row['coherence']:.3f} ({row['coherence_folded']:.3f})"


def setup_line(
    part: str, settings: EvaluationSettings, checkpoints: Mapping[str, str | Path], data_name: str
) -> str:
    """The line under a report's title: data, settings of ``part`` (``likelihood`` or
    ``coherence``), seed and checkpoints, named as given (``prg-evaluate`` names a checkpoint
    in the project relative to the project root, :func:`prg.resources.project_path`)."""
    lk = settings.likelihood
    ckpts = ", ".join(f"{n}: {p}" for n, p in checkpoints.items())
    if part == "likelihood":
        n = lk.n_test if lk.n_test is not None else "all"
        std = "each model's own" if lk.traj_std is None else f"{lk.traj_std:g}"
        what = (
            f"K = {lk.k_marginal} (marginals) / {lk.k_conditional} (conditionals), "
            f"test samples: {n}, trajectory std: {std} (second table: each model's own)"
        )
    else:
        what = f"test samples: {settings.n_test if settings.n_test is not None else 'all'}"
    return (
        f"Data: {data_name} test split; {what}; seed {settings.seed}. {ONE_SEED} "
        f"Checkpoints: {ckpts}."
    )


def report_texts(
    result: Evaluation,
    settings: EvaluationSettings,
    checkpoints: Mapping[str, str | Path],
    data_name: str,
) -> dict[str, str]:
    """File name -> text of every report of the evaluated parts: ``table1.{csv,md}`` (likelihood),
    ``coherence.{csv,md}`` and ``robustness.md`` (coherence; robustness for the first
    generation kind). ``checkpoints``: model name -> checkpoint path, for the setup lines."""
    texts = {}
    if "likelihood" in settings.parts:
        setup = setup_line("likelihood", settings, checkpoints, data_name)
        texts["table1.csv"] = to_csv(result.table1, TABLE1_COLUMNS)
        texts["table1.md"] = table1_markdown(result.table1, setup, settings.likelihood.traj_std)
    if "coherence" in settings.parts:
        setup = setup_line("coherence", settings, checkpoints, data_name)
        texts["coherence.csv"] = to_csv(result.coherence, COHERENCE_COLUMNS)
        texts["coherence.md"] = coherence_markdown(
            result.coherence, result.classifiers, setup, result.smoothness
        )
        kind = next(iter(settings.coherence.temperatures))
        texts["robustness.md"] = robustness_markdown(
            result.coherence, kind, setup, result.shifted_images
        )
        texts["plots/robustness.csv"] = robustness_plot_csv(result.coherence, kind)
        texts["plots/coherence_per_class.csv"] = per_class_plot_csv(result.per_class, kind)
    if "likeness" in settings.parts:
        texts["likeness.csv"] = to_csv(result.likeness, LIKENESS_COLUMNS)
        texts["likeness.md"] = likeness_markdown(result.likeness, settings)
        texts["plots/likeness.csv"] = to_csv(
            [{**r, "row": f"{r['family']} {r['mode']}"} for r in result.likeness],
            ["row", *LIKENESS_MEASURES],
        )
    if "kinematics" in settings.parts:
        from prg.evaluation.kinematics import MEASURES

        texts["kinematics.csv"] = to_csv(result.kinematics, ["group", "paths", *MEASURES])
        texts["kinematics.md"] = kinematics_markdown(result.kinematics, settings)
    if "styles" in settings.parts:
        texts["styles.csv"] = to_csv(result.styles, STYLE_COLUMNS)
        texts["styles.md"] = styles_markdown(result.styles, settings)
    return texts


LIKENESS_COLUMNS = ("family", "mode", *LIKENESS_MEASURES, "classes")
STYLE_COLUMNS = ("family", "seed", "k", "generated", "real", "chance", "writers", "letters")


def likeness_markdown(rows: list[dict], settings: EvaluationSettings) -> str:
    """The likeness table: reference rows first, then each family's modes."""
    if not rows:
        return (
            "# Likeness: generated letters against held-out writers' letters\n\nNot computed: "
            "the test split has at most 3 letters of a class (at least 4 are needed).\n"
        )
    n = settings.likeness.n_per_class
    body = [
        [
            "real letters" if r["family"] == "real" else title(r["family"]),
            f"**{r['mode']}**" if "default" in r["mode"] else r["mode"],
            *(f"{r[m]:.2f}" if r[m] == r[m] else "-" for m in LIKENESS_MEASURES),
        ]
        for r in rows
    ]
    return "\n".join(
        [
            "# Likeness: generated letters against held-out writers' letters",
            "",
            f"{n} letters per class generated from their labels (or drawn from a reference "
            "split), compared class by class with the test split's letters (writers no model "
            "saw) in the normalised 200-d trajectory space, and averaged over the classes. "
            "legible: read as their class by the project's trajectory classifier, shape twins "
            "folded; legible_shape: the same, read by the second reader (the letter drawn as the "
            "dataset's images are, then read by the image classifier: the shape alone, not the "
            "order of the points, which the first also reads); precision / recall: k-NN (k = 3) precision and recall of Kynkäänniemi et "
            "al. 2019; c2st: cross-validated accuracy of a linear classifier telling them from "
            "the real letters (0.5: indistinguishable); spread: median within-class distance, "
            "generated over real (1: as varied as writers). **mean (paper)** is the paper's "
            "decoding; **hand (default)** writes each letter from a real writer's letter "
            "posterior (prg.pipeline.hands). Seed "
            f"{settings.seed}. {ONE_SEED}",
            "",
            _md_table(["family", "mode", *LIKENESS_MEASURES], body),
            "",
        ]
    )


def kinematics_markdown(rows: list[dict], settings: EvaluationSettings) -> str:
    """The kinematics table: the robot's words, planned and executed, beside human motion."""
    from prg.evaluation.kinematics import MEASURES, TARGETS

    k = settings.kinematics
    head = "# Kinematics: how the pen moves, against human motion"
    if not rows:
        return f"{head}\n\nNot computed: no {k.family} checkpoint with hands was evaluated.\n"
    body = [[r["group"], str(r["paths"]), *(f"{r[m]:.3f}" for m in MEASURES)] for r in rows]
    targets = "; ".join(
        f"{m} {'>= ' + str(lo) if hi is None else f'in [{lo}, {hi}]'}"
        for m, (lo, hi) in TARGETS.items()
    )
    return "\n".join(
        [
            head,
            "",
            f"The {k.family} model writes {', '.join(k.words)} (seed i for the i-th word) with the "
            "human timing (the default) and with the paper's constant speed; each is measured as "
            f"planned (the DMP's rollout) and as the simulated {k.robot} executes it (its pen tip "
            "along the word's body), beside the LASA human handwriting demonstrations and the "
            "estimator's controls (white noise, a constant-speed path). Medians over the paths: "
            "the speed-curvature power law's beta and R^2, the speed's coefficient of variation, "
            "speed peaks per second, SPARC (closer to 0 is smoother) and the SNR of a sigma-"
            f"lognormal fit (dB). Targets on the executed pen tip, human timing: {targets}.",
            "",
            _md_table(["group", "paths", *MEASURES], body),
            "",
        ]
    )


def styles_markdown(rows: list[dict], settings: EvaluationSettings) -> str:
    """The style table: per family and k, the writer-identification rates over seeds."""
    s = settings.styles
    if not rows:
        return (
            "# Style: writing in a held-out writer's hand from k of their letters\n\nNot "
            "computed: the test split has fewer than 2 writers, or no model's checkpoint keeps "
            "its training writers' letters.\n"
        )
    body = [
        [
            title(r["family"]),
            str(r["k"]),
            f"{r['generated']:.2f} ± {r['generated_sd']:.2f}",
            f"{r['real']:.2f}",
            f"{r['ratio']:.2f}",
            f"{r['chance']:.2f}",
        ]
        for r in style_summary(rows)
    ]
    return "\n".join(
        [
            "# Style: writing in a held-out writer's hand from k of their letters",
            "",
            f"For each of {len(s.seeds)} seeds, {s.n_eval} letter classes are set aside; a "
            "writer-identification classifier (hand features centred per class, linear) is "
            "trained on the test writers' real letters of the other classes; for each writer, "
            "k of their letters (other classes) are the style, and the model writes the set-"
            "aside classes in it (hand temperature "
            f"{s.temperature}). generated: share of those letters the classifier attributes to "
            "the right writer (mean ± sd over seeds); real: its share on the writers' own "
            "letters of the same classes; ratio: generated over real; chance: one over the "
            f"writers. {ONE_SEED}",
            "",
            _md_table(["family", "k", "generated", "real", "ratio", "chance"], body),
            "",
        ]
    )


def robustness_plot_csv(rows: list[dict], kind: str) -> str:
    """The robustness table for ``dvc plots``: one row per input subset (``subset``), one column
    per model (folded trajectory coherence; empty where the model cannot take the subset)."""
    traj = [r for r in rows if r["target"] == TRAJ and r["kind"] == kind]
    subsets = sorted(dict.fromkeys(r["given"] for r in traj), key=_subset_order)
    models = list(dict.fromkeys(r["model"] for r in traj))
    value = {(r["model"], r["given"]): r["coherence_folded"] for r in traj}
    table = [{"subset": "{" + s + "}", **{m: value.get((m, s)) for m in models}} for s in subsets]
    return to_csv(table, ["subset", *models])


def per_class_plot_csv(per_class: Mapping[tuple[str, str, str, str], Any], kind: str) -> str:
    """Coherence per class for ``dvc plots``: one row per class (``class``: the character), one
    column per model and cross-modal cell (``<model>_<target>_from_<given>``, ``kind``
    generation, exact; reconstruction cells left out)."""
    from prg.alphabet import ALPHABET

    columns = {
        f"{model}_{LETTER[target]}_from_{given.replace(',', '')}": rates
        for (model, target, given, k), rates in per_class.items()
        if k == kind and target != LABEL and LETTER[target] not in given.split(",")
    }
    table = [
        {"class": char, **{name: float(rates[i]) for name, rates in columns.items()}}
        for i, char in enumerate(ALPHABET)
    ]
    return to_csv(table, ["class", *columns])
