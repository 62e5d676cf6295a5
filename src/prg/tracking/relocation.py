"""Moving a SQLite store: its artifact locations are absolute ``file://`` URIs, so after the
artifacts folder moves, :func:`move_store` re-points every location under the old folder
(``python -m prg.tracking move-store``)."""

from __future__ import annotations

import os
import sqlite3
from contextlib import closing
from pathlib import Path

from prg.errors import UsageError
from prg.tracking.store import SQLITE_TIMEOUT_S

# Where an MLflow SQLite store records artifact locations (tables and columns of MLflow 3).
_LOCATIONS = {
    "experiments": ("artifact_location",),
    "runs": ("artifact_uri",),
    "model_versions": ("source", "storage_location"),
    "logged_models": ("artifact_location",),
}


def move_store(
    db: str | os.PathLike, old_artifacts: str | os.PathLike, new_artifacts: str | os.PathLike
) -> int:
    """Re-point a moved SQLite store: every artifact location under ``old_artifacts`` (the
    artifacts folder before the move, as a path) now under ``new_artifacts`` (where it is now).
    Experiments created afterwards get the location that ``logger.artifact_location`` gives.
    Returns how many locations changed; a bad input is a :class:`~prg.errors.UsageError`."""
    db, new = Path(db), Path(new_artifacts).expanduser().resolve()
    old = Path(os.path.abspath(Path(old_artifacts).expanduser()))  # it need not exist any more
    if not db.is_file():
        raise UsageError(f"store {db}: no such file (the mlruns.db to re-point)")
    if not new.is_dir():
        raise UsageError(f"new artifacts folder {new}: no such folder (move mlartifacts first)")
    changed = 0
    with closing(sqlite3.connect(db, timeout=SQLITE_TIMEOUT_S)) as con, con:
        tables = {r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type='table'")}
        if not {"experiments", "runs"} <= tables:
            raise UsageError(f"store {db}: not an MLflow SQLite store (no experiments/runs tables)")
        for table, columns in _LOCATIONS.items():
            present = {r[1] for r in con.execute(f"PRAGMA table_info({table})")}
            for column in (c for c in columns if c in present):
                for before, after in ((old.as_uri(), new.as_uri()), (str(old), str(new))):
                    changed += con.execute(
                        f"UPDATE {table} SET {column} = ? || substr({column}, ?) "
                        f"WHERE substr({column}, 1, ?) = ? "
                        f"AND substr({column}, ?, 1) IN ('', '/')",
                        (after, len(before) + 1, len(before), before, len(before) + 1),
                    ).rowcount
    return changed
