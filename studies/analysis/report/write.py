"""Writing the report folder atomically: report.md, report.html, tidy CSVs, metrics.json,
figures (see :mod:`studies.analysis.report`)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from prg.errors import UsageError
from prg.files import staged_folder
from studies.analysis.analyze import Analysis
from studies.analysis.report.build import build_report, judge_section

REPORT_FILES = ("report.md", "report.html", "tests.csv")


def _csv(frames: list[pd.DataFrame], path: Path) -> None:
    frames = [f for f in frames if f is not None and not f.empty]
    (pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()).to_csv(path, index=False)


def _jsonable(x):
    if isinstance(x, dict):
        return {k: _jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, float) and not np.isfinite(x):
        return None
    return x


def check_out_dir(out: str | Path) -> Path:
    """``out`` as a Path, if it is new, empty or an earlier report folder (else UsageError)."""
    out = Path(out)
    if out.exists() and (
        not out.is_dir() or (any(out.iterdir()) and not (out / "report.md").exists())
    ):
        raise UsageError(
            f"--out {out}: exists and is not an earlier report folder; choose a new or empty folder"
        )
    return out


def write_report(
    analysis: Analysis, out: str | Path, *, paper: bool = True, judge: dict | None = None
) -> Path:
    """Write the report folder atomically (see the module docstring); returns ``out``.
    ``judge``: a ``judge.json`` (:func:`studies.judge.judge`) to report beside the analysis.

    Raises
    ------
    prg.errors.UsageError
        ``out`` exists, is not empty and does not hold an earlier report.
    """
    out = check_out_dir(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    from studies.analysis.paper import reproduce_paper

    reproduced = reproduce_paper() if paper else None
    doc = build_report(analysis, reproduced)
    if judge is not None:
        judge_section(doc, judge)
    with staged_folder(out) as tmp:
        (tmp / "figures").mkdir()
        for b in doc.blocks:
            if b[0] == "fig":
                (tmp / "figures" / b[1]).write_bytes(b[2])
        (tmp / "report.md").write_text(doc.markdown(), encoding="utf-8")
        (tmp / "report.html").write_text(doc.html(), encoding="utf-8")
        tests = []
        for st in analysis.studies:
            tests.append(st.tests)
        _csv(tests, tmp / "tests.csv")
        _csv([st.per_word for st in analysis.studies], tmp / "per_word.csv")
        parts = []
        for st in analysis.studies:
            pp = st.per_participant.merge(
                analysis.attention.rename(
                    columns={"checks": "attention_checks", "failed": "attention_failed"}
                )[["participant_id", "study", "attention_checks", "attention_failed"]],
                on=["participant_id", "study"],
                how="left",
            ).assign(excluded=False)
            parts.append(pp)
        excluded = analysis.attention[analysis.attention["failed_any"]]
        if len(excluded) and analysis.config.exclude_failed_attention:
            parts.append(
                excluded.rename(
                    columns={"checks": "attention_checks", "failed": "attention_failed"}
                )[["study", "participant_id", "attention_checks", "attention_failed"]].assign(
                    excluded=True
                )
            )
        _csv(parts, tmp / "per_participant.csv")
        _csv(
            [
                st.mixed.assign(study=st.kind)
                for st in analysis.studies
                if st.mixed is not None and len(st.mixed)
            ],
            tmp / "mixed_model.csv",
        )
        if reproduced is not None:
            reproduced.to_csv(tmp / "paper_reproduction.csv", index=False)
        metrics = {
            "source": analysis.source,
            "origin": analysis.origin,
            "truth": {st.kind: st.truth.to_dict() for st in analysis.studies if st.truth},
            "studies": {st.kind: _jsonable(st.verdict) for st in analysis.studies},
            "warnings": [w for st in analysis.studies for w in st.warnings],
        }
        if judge is not None:
            metrics["judge"] = {
                "observer_pick_rate": judge["observer"]["pick_rate"],
                "observer_ci95": judge["observer"]["ci95"],
                "c2st": {k: v["balanced_accuracy"] for k, v in judge["c2st"].items()},
            }
        (tmp / "metrics.json").write_text(json.dumps(metrics, indent=2) + "\n", encoding="utf-8")
    return out
