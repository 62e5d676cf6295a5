"""Read and check a long-format responses CSV (see :mod:`studies.analysis.schema`).

Every problem found is a one-line description naming the file, the line (the header is line 1)
and the column, and saying what is accepted, e.g.
``responses.csv line 17: confidence 7 is outside 1-5 (accepted: an integer 1-5)``.
The whole file is checked before anything is analysed; if it has problems,
:class:`ResponseFileError` is raised with the first three in its one-line message (``; ``
separated, then ``(and N more problems)``) and all of them in ``.problems``.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from prg.errors import UsageError
from studies.analysis.schema import (
    CONFIDENCE_RANGE,
    FALSE_STRINGS,
    N_OPTIONS,
    ORIGINS,
    PILOT_SUFFIX,
    READABILITY,
    SIMULATED_VERSION,
    STUDY_COLUMNS,
    STUDY_KINDS,
    STUDY_REQUIRED,
    TRUE_STRINGS,
    TURING,
    kind_from_columns,
    normalise_text,
    origin_of,
    study_kind,
)

MAX_LISTED = 3
WRITER_ALIASES = {"human": "human", "robot": "robot", "prg": "robot", "machine": "robot"}


class ResponseFileError(UsageError):
    """The responses file has problems; ``problems`` lists every one (one line each)."""

    def __init__(self, path: str, problems: list[str]):
        self.path = path
        self.problems = list(problems)
        shown = "; ".join(problems[:MAX_LISTED])
        more = len(problems) - MAX_LISTED
        tail = f" (and {more} more problem{'s' if more > 1 else ''})" if more > 0 else ""
        super().__init__(f"{path} {shown}{tail}")


@dataclass
class Responses:
    """A checked responses file.

    Attributes
    ----------
    frame : DataFrame
        One row per trial, typed: ``chose_robot``, ``confidence``, ``correct`` and
        ``attention_pass`` are float (1/0, NaN where empty), ``is_attention_check`` bool,
        ``study`` the study kind, ``line`` the row's line in the file.
    kinds : list of str
        The studies present (``turing``, ``readability``).
    notes : list of str
        What the reader did that the report should say (missing optional columns, derived
        values, rows of another study dropped).
    origin : str
        Where every row comes from (:data:`~studies.analysis.schema.ORIGINS`): ``study``,
        ``pilot`` (a pilot build's page) or ``simulated``.
    """

    path: str
    frame: pd.DataFrame
    kinds: list[str]
    notes: list[str] = field(default_factory=list)
    origin: str = "study"


def _read_csv(path: str | Path) -> pd.DataFrame:
    p = Path(path)
    if not p.is_file():
        raise UsageError(f"{path}: no such responses file (expected a long-format CSV)")
    try:
        with p.open(newline="", encoding="utf-8-sig") as fh:
            header = next(csv.reader(fh), None)
    except UnicodeDecodeError:
        raise UsageError(f"{path}: not a UTF-8 text file (expected a long-format CSV)") from None
    if not header:
        raise UsageError(f"{path}: empty file (expected a header line and one row per trial)")
    names = [h.strip() for h in header]
    dupes = sorted({n for n in names if names.count(n) > 1})
    if dupes:
        raise UsageError(f"{path} line 1: column {dupes[0]!r} appears more than once")
    try:
        df = pd.read_csv(
            p, dtype=str, keep_default_na=False, encoding="utf-8-sig", skipinitialspace=False
        )
    except pd.errors.ParserError as err:
        msg = " ".join(str(err).split()).replace("Error tokenizing data. C error: ", "")
        raise UsageError(f"{path}: not a well-formed CSV ({msg})") from None
    df.columns = names
    if df.empty:
        raise UsageError(f"{path}: no rows after the header (expected one row per trial)")
    return df


def _bool(s: pd.Series) -> tuple[pd.Series, pd.Series]:
    """(values 1.0/0.0/NaN, mask of cells that are neither empty nor a boolean)."""
    low = s.str.lower()
    val = pd.Series(np.nan, index=s.index)
    val[low.isin(TRUE_STRINGS)] = 1.0
    val[low.isin(FALSE_STRINGS)] = 0.0
    bad = (low != "") & val.isna()
    return val, bad


def _number(s: pd.Series, *, integer: bool) -> tuple[pd.Series, pd.Series]:
    """(values, mask of non-empty cells that are not numbers / not whole numbers)."""
    val = pd.to_numeric(s.where(s != ""), errors="coerce").astype(float)
    bad = (s != "") & (val.isna() | ~np.isfinite(val))
    if integer:
        bad |= (s != "") & val.notna() & (val != np.round(val))
    return val, bad


def _check_rows(
    df: pd.DataFrame, kind: str, n_options: int, problems: list[tuple[int, str]], notes: list[str]
) -> pd.DataFrame:
    """Parse and range-check the rows of one study; appends (line, text) problems."""
    out = pd.DataFrame(index=df.index)
    out["line"] = df["line"]
    out["study"] = kind
    lines = df["line"]

    def report(mask: pd.Series, text) -> None:
        for i in mask[mask].index:
            problems.append((int(lines[i]), text(i)))

    def boolean(col: str, accepted: str = "true/false (1/0)") -> pd.Series:
        """``df[col]`` as 1.0/0.0 (NaN where empty); any other value is reported."""
        val, bad = _bool(df[col])
        report(bad, lambda i: f"{col} {df.at[i, col]!r} is not {accepted}")
        return val

    for col in ("participant_id", "word"):
        report(df[col] == "", lambda i, c=col: f"{c} is empty (accepted: a non-empty value)")
        out[col] = df[col]
    for col in ("session_id", "list_id", "timestamp", "app_version"):
        out[col] = df.get(col, "")

    if "is_attention_check" in df:
        out["is_attention_check"] = boolean("is_attention_check").fillna(0.0).astype(bool)
    else:
        out["is_attention_check"] = False
    if "attention_pass" in df:
        passed = boolean("attention_pass", "true/false (1/0) or empty")
        out["attention_pass"] = passed.where(out["is_attention_check"])
    else:
        out["attention_pass"] = np.nan
    check = out["is_attention_check"]
    regular = ~check

    for col, integer, low, accepted in (
        ("trial", True, 0, "an integer >= 0"),
        ("rt_ms", False, 0, "a number >= 0"),
        ("seed", True, None, "an integer"),
    ):
        if col not in df:
            out[col] = np.nan
            continue
        val, bad = _number(df[col], integer=integer)
        report(bad, lambda i, c=col, a=accepted: f"{c} {df.at[i, c]!r} is not {a}")
        if low is not None:
            report(
                val < low,
                lambda i, c=col, a=accepted, lo=low: (
                    f"{c} {df.at[i, c]} is below {lo} (accepted: {a})"
                ),
            )
        out[col] = val

    if kind == TURING:
        hi = n_options - 1
        for col in ("robot_index", "chosen_index"):
            if col not in df:
                out[col] = np.nan
                continue
            val, bad = _number(df[col], integer=True)
            report(bad, lambda i, c=col: f"{c} {df.at[i, c]!r} is not an integer 0-{hi}")
            report(
                (val < 0) | (val > hi),
                lambda i, c=col: (
                    f"{c} {df.at[i, c]} is outside 0-{hi} (0-based position among {n_options} samples)"
                ),
            )
            out[col] = val
        have_idx = out["robot_index"].notna() & out["chosen_index"].notna()
        from_idx = (out["chosen_index"] == out["robot_index"]).astype(float).where(have_idx)
        if "chose_robot" in df:
            chose = boolean("chose_robot")
            clash = chose.notna() & have_idx & (chose != from_idx)
            report(
                clash,
                lambda i: (
                    f"chose_robot {df.at[i, 'chose_robot']} contradicts chosen_index "
                    f"{out.at[i, 'chosen_index']:.0f} vs robot_index {out.at[i, 'robot_index']:.0f}"
                ),
            )
            filled = chose.isna() & have_idx & regular
            if filled.any():
                notes.append(
                    f"chose_robot was empty on {int(filled.sum())} trial rows; taken from chosen_index == robot_index"
                )
            chose = chose.fillna(from_idx)
        else:
            chose = from_idx
            notes.append("no chose_robot column; taken from chosen_index == robot_index")
        raw = df["chose_robot"] if "chose_robot" in df else pd.Series("", index=df.index)
        report(
            regular & chose.isna() & (raw == ""),
            lambda i: (
                "chose_robot is empty (accepted: true/false, or both robot_index and chosen_index)"
            ),
        )
        out["chose_robot"] = chose
        lo_c, hi_c = CONFIDENCE_RANGE
        val, bad = _number(df["confidence"], integer=True)
        report(
            bad, lambda i: f"confidence {df.at[i, 'confidence']!r} is not an integer {lo_c}-{hi_c}"
        )
        report(
            (val < lo_c) | (val > hi_c),
            lambda i: (
                f"confidence {df.at[i, 'confidence']} is outside {lo_c}-{hi_c} (accepted: an integer {lo_c}-{hi_c})"
            ),
        )
        report(
            regular & (df["confidence"] == ""),
            lambda i: f"confidence is empty (accepted: an integer {lo_c}-{hi_c})",
        )
        out["confidence"] = val
    else:
        writer = df["writer"].str.lower().map(WRITER_ALIASES)
        report(
            (df["writer"] != "") & writer.isna(),
            lambda i: f"writer {df.at[i, 'writer']!r} is not human or robot",
        )
        report(
            regular & (df["writer"] == ""), lambda i: "writer is empty (accepted: human or robot)"
        )
        out["writer"] = writer
        typed = df.get("typed_text")
        out["typed_text"] = typed if typed is not None else ""
        derived = None
        if typed is not None:
            derived = pd.Series(
                [float(normalise_text(t) == normalise_text(w)) for t, w in zip(typed, df["word"])],
                index=df.index,
            )
        if "correct" in df:
            corr = boolean("correct")
            if derived is not None:
                filled = corr.isna() & (df["correct"] == "")
                if (filled & regular).any():
                    notes.append(
                        f"correct was empty on {int((filled & regular).sum())} rows; scored from typed_text"
                    )
                corr = corr.where(~filled, derived)
        elif derived is not None:
            corr = derived
            notes.append(
                "no correct column; scored typed_text against word (trimmed, case-insensitive)"
            )
        else:
            corr = pd.Series(np.nan, index=df.index)
        raw = df["correct"] if "correct" in df else pd.Series("", index=df.index)
        report(
            regular & corr.isna() & (raw == ""),
            lambda i: "correct is empty (accepted: true/false, or a typed_text column to score)",
        )
        out["correct"] = corr
    return out


def _duplicates(out: pd.DataFrame, problems: list[tuple[int, str]]) -> None:
    """One problem per repeated (study, participant, trial) — or (participant, word) without trials."""
    use_trial = bool(out["trial"].notna().all())
    keys = (
        ["study", "participant_id", "trial"] if use_trial else ["study", "participant_id", "word"]
    )
    pool = out if use_trial else out[~out["is_attention_check"]]
    dup = pool[pool.duplicated(keys, keep=False)]
    for _, grp in dup.groupby(keys, sort=False, dropna=False):
        first, *rest = grp["line"].tolist()
        what = f"trial {grp['trial'].iloc[0]:.0f}" if use_trial else f"word {grp['word'].iloc[0]!r}"
        for line in rest:
            problems.append(
                (
                    int(line),
                    f"duplicate trial: participant {grp['participant_id'].iloc[0]!r} {what} is also on "
                    f"line {first} (each participant's trial appears once)",
                )
            )


def load_responses(
    path: str | Path, kind: str | None = None, n_options: int = N_OPTIONS
) -> Responses:
    """Read, check and type a long-format responses CSV.

    Parameters
    ----------
    path : str or Path
        The CSV (header line, one row per trial; columns of :mod:`studies.analysis.schema`).
    kind : {"turing", "readability"}, optional
        Analyse only this study's rows. Default: the kinds named in the ``study`` column, or
        guessed from the columns when there is none.
    n_options : int
        Samples per Turing trial (``robot_index`` and ``chosen_index`` are 0-based below it).

    Returns
    -------
    Responses

    Raises
    ------
    ResponseFileError
        Missing columns, unreadable cells, out-of-range answers or duplicate trials (all listed
        in ``.problems``; the first three in the message).
    prg.errors.UsageError
        The file is missing, empty or not a CSV.
    """
    return check_responses(_read_csv(path), str(path), kind=kind, n_options=n_options)


def check_responses(
    table: pd.DataFrame,
    name: str = "responses",
    kind: str | None = None,
    n_options: int = N_OPTIONS,
) -> Responses:
    """Check and type a responses table already in memory (cells as written to the CSV).

    The same checks as :func:`load_responses`; ``name`` stands for the file in messages and
    row ``i`` of ``table`` is reported as line ``i + 2`` (the line it has in the CSV).
    """
    if table.empty:
        raise UsageError(f"{name}: no rows (expected one row per trial)")
    df = table.reset_index(drop=True).copy()
    df.columns = [str(c).strip() for c in df.columns]
    for col in df.columns:
        df[col] = df[col].astype(object).where(df[col].notna(), "").astype(str).str.strip()
    df.insert(0, "line", np.arange(2, len(df) + 2))
    notes: list[str] = []
    if kind is not None and kind not in STUDY_KINDS:
        raise UsageError(f"study kind {kind!r} is not one of {', '.join(STUDY_KINDS)}")
    if "study" in df.columns:
        kinds_col = df["study"].map(study_kind)
        bad = kinds_col.isna()
        if bad.any():
            problems = [
                f"line {df.at[i, 'line']}: study {df.at[i, 'study']!r} is not turing or readability"
                for i in bad[bad].index
            ]
            raise ResponseFileError(name, problems)
        if kind is not None:
            other = kinds_col != kind
            if other.all():
                found = ", ".join(sorted(set(kinds_col)))
                raise UsageError(f"{name}: no {kind} rows (the study column names {found})")
            if other.any():
                notes.append(f"{int(other.sum())} rows of another study were left out")
            df, kinds_col = df[~other], kinds_col[~other]
    else:
        guessed = kind or kind_from_columns(list(df.columns))
        if guessed is None:
            raise UsageError(
                f"{name}: cannot tell which study the rows belong to (no study column); "
                "give --study conf/study/<turing|readability>.yaml"
            )
        kinds_col = pd.Series(guessed, index=df.index)
    kinds = [k for k in STUDY_KINDS if (kinds_col == k).any()]

    problems: list[tuple[int, str]] = []
    parts = []
    for k in kinds:
        rows = df[kinds_col == k]
        missing = [c for c in STUDY_REQUIRED[k] if c not in rows.columns]
        if (
            k == TURING
            and "chose_robot" not in rows.columns
            and not {"robot_index", "chosen_index"} <= set(rows.columns)
        ):
            missing.append("chose_robot")
        if k == READABILITY and "correct" not in rows.columns and "typed_text" not in rows.columns:
            missing.append("correct")
        if missing:
            raise ResponseFileError(
                name,
                [
                    f"line 1: missing column {c} (the {k} study needs "
                    f"{', '.join(STUDY_REQUIRED[k])} and "
                    f"{'chose_robot (or robot_index and chosen_index)' if k == TURING else 'correct (or typed_text)'})"
                    for c in missing
                ],
            )
        absent = [c for c in STUDY_COLUMNS[k] if c not in rows.columns]
        if absent:
            notes.append(f"{k}: optional columns absent: {', '.join(absent)}")
        parts.append(_check_rows(rows, k, n_options, problems, notes))
    out = pd.concat(parts).sort_values("line", kind="stable").reset_index(drop=True)
    _duplicates(out, problems)
    if problems:
        problems.sort(key=lambda p: p[0])
        raise ResponseFileError(name, [f"line {line}: {text}" for line, text in problems])
    origin = _one_origin(df, name)
    return Responses(path=name, frame=out, kinds=kinds, notes=notes, origin=origin)


def _one_origin(df: pd.DataFrame, name: str) -> str:
    """The origin all rows share (by ``app_version``); a mixture raises ResponseFileError."""
    if "app_version" not in df:
        return "study"
    origins = df["app_version"].map(origin_of)
    found = [o for o in ORIGINS if (origins == o).any()]
    if len(found) == 1:
        return found[0]
    where = {"study": "the study's page", "pilot": "a pilot build", "simulated": "the simulator"}
    parts = [
        f"{int((origins == o).sum())} rows from {where[o]} "
        f"(first on line {int(df.loc[origins == o, 'line'].iloc[0])})"
        for o in found
    ]
    raise ResponseFileError(
        name,
        [
            f"mixes {' and '.join(parts)}: never analysed together; analyse each in its own "
            f"file (app_version {SIMULATED_VERSION!r}: the simulator; ending {PILOT_SUFFIX!r}: "
            "a pilot build; any other: the study)"
        ],
    )


def attention_summary(frame: pd.DataFrame) -> pd.DataFrame:
    """Per participant: attention checks seen, passed, failed (one row per participant).

    Columns: participant_id, study, checks, passed, failed, unknown, failed_any.
    """
    rows = frame[frame["is_attention_check"]]
    parts = frame[["participant_id", "study"]].drop_duplicates()
    if rows.empty:
        summary = parts.assign(checks=0, passed=0, failed=0, unknown=0)
    else:
        g = rows.groupby(["participant_id", "study"])["attention_pass"]
        counts = pd.DataFrame(
            {
                "checks": g.size(),
                "passed": g.apply(lambda s: int((s == 1).sum())),
                "failed": g.apply(lambda s: int((s == 0).sum())),
                "unknown": g.apply(lambda s: int(s.isna().sum())),
            }
        ).reset_index()
        summary = parts.merge(counts, on=["participant_id", "study"], how="left").fillna(0)
    for c in ("checks", "passed", "failed", "unknown"):
        summary[c] = summary[c].astype(int)
    summary["failed_any"] = summary["failed"] > 0
    return summary.reset_index(drop=True)


def analysis_rows(
    frame: pd.DataFrame, *, include_attention_rows: bool = False, exclude_failed: bool = True
) -> tuple[pd.DataFrame, list[str]]:
    """The rows to analyse and one note per exclusion made.

    Attention-check rows are left out unless ``include_attention_rows``; participants who failed
    any attention check are left out when ``exclude_failed`` (and always named in the notes).
    """
    notes = []
    keep = pd.Series(True, index=frame.index)
    n_check = int(frame["is_attention_check"].sum())
    if n_check and not include_attention_rows:
        keep &= ~frame["is_attention_check"]
        notes.append(f"{n_check} attention-check rows left out of the analysis")
    att = attention_summary(frame)
    failed = att.loc[att["failed_any"], "participant_id"].unique().tolist()
    if failed:
        listed = ", ".join(map(str, failed[:10])) + (" ..." if len(failed) > 10 else "")
        if exclude_failed:
            keep &= ~frame["participant_id"].isin(failed)
            notes.append(
                f"{len(failed)} participants failed an attention check and were excluded: {listed}"
            )
        else:
            notes.append(f"{len(failed)} participants failed an attention check (kept): {listed}")
    used = frame[keep].reset_index(drop=True)
    # rows kept from attention checks may have empty outcomes
    outcome = [c for c in ("chose_robot", "correct") if c in used]
    if outcome:
        used = used[used[outcome].notna().any(axis=1)].reset_index(drop=True)
    return used, notes
