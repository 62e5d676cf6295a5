"""An evaluation's tables from its flat metrics (``reports/metrics.json``: ``<family>/logp_T``,
``<family>/coherence_folded_T_given_S`` ...): Table I in the paper's convention and under each
model's own std, coherence, missing-modality robustness, images moved off-centre, smoothness,
likeness to held-out writers and style.

The family titles, Table I's cells, column titles and paper values, and the likeness measures
come from :mod:`prg.evaluation.reports` (and the modules it takes them from); the tables
themselves do not: those reports render an evaluation's result rows (estimates with their
standard errors, rates to three decimals, one table per model), these a snapshot's flat metrics
(one decimal, percentages, '-' where a snapshot lacks a metric).
"""

from __future__ import annotations

import re

from prg.evaluation.likelihood import MODEL_STD_SUFFIX, PAPER_TABLE1, TABLE1_CELLS
from prg.evaluation.modes import LIKENESS_MEASURES
from prg.evaluation.reports import FAMILY_TITLES, _cell_title
from prg.models.modalities import TRAJ

from .common import number, table
from .snapshot import PIPELINE_FAMILIES

# Table I's cells (logp_T, logp_S ... logp_I_given_T) and those with a trajectory target
TRAJ_CELLS = [c for c, (target, _) in TABLE1_CELLS.items() if target == TRAJ]
COHERENCE_CELLS = [
    "T_given_S",
    "T_given_I",
    "T_given_SI",
    "I_given_T",
    "S_given_T",
    "I_given_S",
    "T_given_T",
]
# trajectory coherence from every subset of inputs (missing-modality robustness)
ROBUSTNESS_SUBSETS = ["S", "I", "SI", "T", "TS", "TI", "TSI"]
ROUGHNESS_CELLS = ["T_given_S", "T_given_I"]
TEST_ROUGHNESS = "test_split/roughness"


def table1_markdown(evaluate: dict, models: dict[str, dict]) -> str:
    """Table I in the paper's convention (unit-variance trajectory Gaussian, the paper's values
    in parentheses) and the trajectory cells under each model's own std."""

    def main_cell(family: str, cell: str) -> str:
        ours = number(evaluate, f"{family}/{cell}", ".1f")
        paper = PAPER_TABLE1.get(family, {}).get(cell)
        return ours if ours == "-" or paper is None else f"{ours} ({paper:.2f})"

    main = table(
        ["model", *map(_cell_title, TABLE1_CELLS), "val loss"],
        [
            [
                FAMILY_TITLES[family],
                *(main_cell(family, c) for c in TABLE1_CELLS),
                number(models.get(family, {}), "val_loss", ".1f"),
            ]
            for family in PIPELINE_FAMILIES
        ],
    )
    own = table(
        ["model", *map(_cell_title, TRAJ_CELLS)],
        [
            [
                FAMILY_TITLES[family],
                *(number(evaluate, f"{family}/{c}{MODEL_STD_SUFFIX}", ".1f") for c in TRAJ_CELLS),
            ]
            for family in PIPELINE_FAMILIES
        ],
    )
    return "\n".join(
        [
            "**Table I** (importance-weighted log-likelihoods, nats; higher is better) in the "
            "paper's convention: trajectory cells under a unit-variance Gaussian with its "
            "normalising constant, the paper's values in parentheses (its label and image terms "
            "follow another convention, see *Evaluation*); and the validation loss of each model:",
            "",
            main,
            "",
            "The trajectory cells under each model's own std (0.1, the one it is trained with), "
            "from the same importance samples:",
            "",
            own,
        ]
    )


def coherence_markdown(evaluate: dict) -> str:
    """Exact and shape-twin-folded coherence, and the roughness ratios of decoded letters."""

    def variants(family: str) -> list[tuple[str, str]]:
        """(row title, key infix) of the family's generation kinds shown: the paper's posterior
        mean, and the imputed one where the snapshot has it."""
        rows = [(FAMILY_TITLES[family], "")]
        if any(k.startswith(f"{family}/coherence_imputed_") for k in evaluate):
            rows.append((f"{FAMILY_TITLES[family]}, imputed", "imputed_"))
        return rows

    def cell(family: str, kind: str, c: str) -> str:
        exact = number(evaluate, f"{family}/coherence_{kind}{c}", ".0%")
        folded = number(evaluate, f"{family}/coherence_folded_{kind}{c}", ".0%")
        return "-" if exact == folded == "-" else f"{exact} / {folded}"

    coherence = table(
        ["model", *(c.replace("_given_", " from ") for c in COHERENCE_CELLS)],
        [
            [title, *(cell(f, kind, c) for c in COHERENCE_CELLS)]
            for f in PIPELINE_FAMILIES
            for title, kind in variants(f)
        ],
    )
    roughness = table(
        ["model", *(c.replace("_given_", " from ") for c in ROUGHNESS_CELLS)],
        [
            [
                title,
                *(
                    number(evaluate, f"{f}/roughness_ratio_{kind}{c}", ".2f")
                    for c in ROUGHNESS_CELLS
                ),
            ]
            for f in PIPELINE_FAMILIES
            for title, kind in variants(f)
        ],
    )
    robustness = table(
        ["model", *(f"{{{','.join(subset)}}}" for subset in ROBUSTNESS_SUBSETS)],
        [
            [
                title,
                *(
                    number(evaluate, f"{f}/coherence_folded_{kind}T_given_{subset}", ".0%")
                    for subset in ROBUSTNESS_SUBSETS
                ),
            ]
            for f in PIPELINE_FAMILIES
            for title, kind in variants(f)
        ],
    )
    shifted = _shifted_images_markdown(evaluate)
    return "\n".join(
        [
            "**Cross-modal coherence** (the generated modality classified as the given label; "
            "exact / with shape twins such as o/O/0 counted right; posterior mean, and for "
            "MUSE also *imputed*: after 20 rounds of imputing the missing modalities, as "
            "`prg-write` decodes):",
            "",
            coherence,
            "",
            "**Missing-modality robustness**: trajectory coherence (folded) from each subset of "
            "inputs a model accepts ('-' where it cannot take it; subsets with T are "
            "reconstructions):",
            "",
            robustness,
            "",
            *shifted,
            "**Smoothness**: roughness ratio of the letters decoded from labels or images "
            "(posterior mean): their median roughness over the test letters' median roughness "
            f"({number(evaluate, TEST_ROUGHNESS, '.3f')}); 1 is as smooth as the data, the "
            "target is <= 2:",
            "",
            roughness,
        ]
    )


def _shifted_images_markdown(evaluate: dict) -> list[str]:
    """Coherence from test images moved off-centre (lines, then a blank one; none for a snapshot
    made before the evaluation had it)."""
    shifts = sorted(
        {
            int(k.rsplit("_shift", 1)[1])
            for k in evaluate
            if "/coherence_folded_T_given_I_shift" in k
        }
    )
    if not shifts:
        return []
    cells = [(c, s) for c in ("T_given_I", "S_given_I") for s in shifts]
    shifted = table(
        [
            "model",
            *(
                f"{c.replace('_given_', ' from ')}, " + (f"<= {s} px" if s else "as is")
                for c, s in cells
            ),
        ],
        [
            [
                FAMILY_TITLES[f],
                *(number(evaluate, f"{f}/coherence_folded_{c}_shift{s}", ".0%") for c, s in cells),
            ]
            for f in PIPELINE_FAMILIES
            if f"{f}/coherence_folded_T_given_I_shift0" in evaluate
        ],
    )
    return [
        "**Images moved off-centre**: coherence (folded) of what a model generates from a test "
        "image alone, as rendered and moved by a random offset of up to 1 or 2 pixels per axis "
        "(`robustness.md`):",
        "",
        shifted,
        "",
    ]


def likeness_markdown(evaluate: dict) -> str:
    """The likeness table (``<family>/likeness_<mode>_<measure>``) and the style rates
    (``<family>/style_k<k>_generated`` ...), where the snapshot has them (older ones do not)."""
    pattern = re.compile(r"^([^/]+)/likeness_(.+)_legible$")
    rows = [m.groups() for k in evaluate if (m := pattern.match(k))]
    if not rows:
        return ""
    families = ["real", *PIPELINE_FAMILIES]
    modes = ["val_writers", "train_originals", "mean", "imputed", "sampled_t0.5", "sampled_t1"]
    modes += ["hand_t0", "hand", "hand_t1"]
    rows.sort(key=lambda r: (families.index(r[0]), modes.index(r[1]) if r[1] in modes else 99))
    body = []
    for family, mode in rows:
        name = "real letters" if family == "real" else family
        shown = mode.replace("_", " ").replace(" t", " T=")
        if mode == "hand":
            shown = "**hand (default)**"
        elif mode == "mean":
            shown = "mean (the paper)"
        cells = [
            number(evaluate, f"{family}/likeness_{mode}_{m}", ".2f") for m in LIKENESS_MEASURES
        ]
        body.append([name, shown, *cells])
    lines = [
        "**Likeness to held-out writers** (`reports/likeness.md`): 10 letters per class from "
        "their labels against the test split's letters; legible = read right by the trajectory "
        "classifier (folded), legible_shape = by the second reader (the letter drawn, then read by "
        "the image classifier); k-NN precision / recall (k = 3); C2ST = linear classifier's "
        "accuracy telling them from real (0.5 ideal); spread = within-class distance over the "
        "real letters' (1 ideal). The first rows are real letters scored the same way.",
        "",
        table(["family", "mode", *LIKENESS_MEASURES], body),
    ]
    style = re.compile(r"^([^/]+)/style_k(\d+)_generated$")
    found = [m.groups() for k in evaluate if (m := style.match(k))]
    found.sort(
        key=lambda r: (list(FAMILY_TITLES).index(r[0]) if r[0] in FAMILY_TITLES else 99, int(r[1]))
    )
    if found:
        lines += [
            "",
            "**A writer's style from k letters** (`reports/styles.md`): share of letters written "
            "in a held-out writer's style that a writer-identification classifier attributes to "
            "that writer, over the same for the writer's own letters (ratio).",
            "",
            table(
                ["family", "k", "generated", "own letters", "ratio"],
                [
                    [
                        f,
                        k,
                        f"{evaluate[f'{f}/style_k{k}_generated']:.2f}",
                        f"{evaluate[f'{f}/style_real']:.2f}",
                        f"{evaluate[f'{f}/style_k{k}_ratio']:.2f}",
                    ]
                    for f, k in found
                ],
            ),
        ]
    return "\n".join(lines)
