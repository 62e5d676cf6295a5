"""Report tables of an evaluation: Table I (with the paper's values), coherence, robustness.

Pure functions from result rows (lists of dicts) to CSV/Markdown text; the caller writes them.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence

from prg.evaluation.likelihood import DENSITY_CONVENTION, TABLE1_CELLS
from prg.models.base import LETTER
from prg.models.likelihoods import MODALITIES

FAMILY_TITLES = {
    "cvae": "PRG_CVAE(T,S)",
    "avae_ts": "PRG_AVAE(T,S)",
    "avae_ti": "PRG_AVAE(T,I)",
    "muse": "PRG_MUSE(T,S,I)",
}

# Table I of Vital et al. (2022): augmented UJI Char Pen 2 test set, K = 1000 / 5000.
PAPER_TABLE1: dict[str, dict[str, float]] = {
    "cvae": {"logp_T_given_S": -192.75},
    "avae_ts": {
        "logp_T": -197.55,
        "logp_S": -4.17,
        "logp_T_given_S": -189.28,
        "logp_S_given_T": 1.94,
    },
    "avae_ti": {
        "logp_T": -197.69,
        "logp_I": -743.57,
        "logp_T_given_I": -186.28,
        "logp_I_given_T": -730.44,
    },
    "muse": {
        "logp_T": -198.04,
        "logp_S": -4.53,
        "logp_I": -742.49,
        "logp_T_given_S": -198.10,
        "logp_T_given_I": -193.63,
        "logp_S_given_T": 1.96,
        "logp_I_given_T": -735.02,
    },
}

PAPER_NOTE = (
    "Paper values (in parentheses) come from models trained on the augmented UJI Char Pen 2 "
    "data with the authors' density convention, which is not fully stated; their positive "
    "log p(x_S | x_T) is impossible for a normalised categorical, so their label (and likely "
    "image) terms differ from ours by constants. Compare orderings between families, not "
    "absolute numbers; our data may also differ (synthetic substitute unless data=uji)."
)


def title(family: str) -> str:
    return FAMILY_TITLES.get(family, family)


def subset_name(given: Sequence[str]) -> str:
    """('label', 'image') -> 'S,I' (the paper's letters, in T, S, I order)."""
    return ",".join(LETTER[m] for m in MODALITIES if m in given)


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


def table1_markdown(rows: list[dict], setup: str) -> str:
    """Wide Table I: one row per evaluated model, one column per cell, ``ours (paper)``."""
    names = list(dict.fromkeys(r["model"] for r in rows))
    by_key = {(r["model"], r["cell"]): r for r in rows}
    header = ["model", *[_cell_title(c) for c in TABLE1_CELLS]]
    body = []
    for name in names:
        family = next(r["family"] for r in rows if r["model"] == name)
        cells = []
        for cell in TABLE1_CELLS:
            row = by_key.get((name, cell))
            paper = PAPER_TABLE1.get(family, {}).get(cell)
            text = "-" if row is None else f"{row['value']:.2f} ± {row['sem']:.2f}"
            if paper is not None:
                text += f" ({paper:.2f})"
            cells.append(text)
        body.append([title(family) if name == family else f"{name}: {title(family)}", *cells])
    return (
        "\n\n".join(
            [
                "# Table I: importance-weighted log-likelihoods (higher is better)",
                setup,
                _md_table(header, body),
                f"Density convention: {DENSITY_CONVENTION}",
                PAPER_NOTE,
            ]
        )
        + "\n"
    )


def _cell_title(cell: str) -> str:
    target, given = TABLE1_CELLS[cell]
    inner = f"x_{LETTER[target]}" + (f" \\| x_{subset_name(given)}" if given else "")
    return f"log p({inner})"


def coherence_markdown(rows: list[dict], classifier_info: dict, setup: str) -> str:
    """Per model: a row per (target, input subset), a column per generation kind."""
    kinds = list(dict.fromkeys(r["kind"] for r in rows))
    parts = [
        "# Cross-modal coherence",
        setup,
        "Fraction of generated samples that the independent classifier assigns to the "
        "conditioning class (labels: the decoded label's accuracy). Reconstruction cells "
        "(target among the inputs) are marked with *.",
        _classifier_lines(classifier_info),
    ]
    for name in dict.fromkeys(r["model"] for r in rows):
        mine = [r for r in rows if r["model"] == name]
        family = mine[0]["family"]
        cells = list(dict.fromkeys((r["target"], r["given"]) for r in mine))
        value = {(r["target"], r["given"], r["kind"]): r["coherence"] for r in mine}
        body = []
        for target, given in cells:
            star = "*" if LETTER[target] in given.split(",") else ""
            body.append(
                [f"{LETTER[target]} given {{{given}}}{star}"]
                + [f"{value[(target, given, k)]:.3f}" for k in kinds]
            )
        parts += [f"## {name}: {title(family)}", _md_table(["generated", *kinds], body)]
    return "\n\n".join(parts) + "\n"


def _classifier_lines(info: dict) -> str:
    lines = ["Classifiers (trained on the training split, scored on the real test split):"]
    for modality, meta in info.items():
        lines.append(
            f"- {modality}: test accuracy {meta['test_accuracy']:.3f}"
            + (
                f" (case twins folded: {meta['test_folded_accuracy']:.3f})"
                if "test_folded_accuracy" in meta
                else ""
            )
        )
    return "\n".join(lines)


def _subset_order(subset: str) -> tuple:
    """Cross-modal subsets first, then those holding T; smaller first; T, S, I order."""
    letters = subset.split(",")
    return ("T" in letters, len(letters), ["TSI".index(c) for c in letters])


def robustness_markdown(rows: list[dict], kind: str, setup: str) -> str:
    """Trajectory coherence for every input subset each model accepts (missing modalities)."""
    traj = [r for r in rows if r["target"] == "traj" and r["kind"] == kind]
    subsets = sorted(dict.fromkeys(r["given"] for r in traj), key=_subset_order)
    value = {(r["model"], r["given"]): r["coherence"] for r in traj}
    body = []
    for name in dict.fromkeys(r["model"] for r in traj):
        family = next(r["family"] for r in traj if r["model"] == name)
        body.append(
            [title(family) if name == family else name]
            + [f"{value[(name, s)]:.3f}" if (name, s) in value else "-" for s in subsets]
        )
    header = ["model", *[f"{{{s}}}" + ("*" if "T" in s.split(",") else "") for s in subsets]]
    return (
        "\n\n".join(
            [
                "# Missing-modality robustness: coherence of generated trajectories",
                setup,
                f"Each column is the subset of inputs given ({kind} generation); '-' where the model "
                "cannot take that subset. * marks subsets that contain the trajectory itself "
                "(reconstruction).",
                _md_table(header, body),
            ]
        )
        + "\n"
    )
