"""``python -m prg.tracking move-store DB OLD_ARTIFACTS NEW_ARTIFACTS`` (re-point a moved SQLite
store, :func:`prg.tracking.move_store`) and ``python -m prg.tracking log-pending FILE`` (log a run
that a command handed to the background, :func:`prg.tracking.log_pending_run`).
``python -m prg.commands.tracking`` runs the same :func:`main`."""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

from prg.errors import UsageError
from prg.tracking import log_pending_run, move_store

USAGE = (
    "python -m prg.tracking move-store DB OLD_ARTIFACTS NEW_ARTIFACTS"
    " | python -m prg.tracking log-pending FILE"
)


def main(argv: list[str]) -> int:
    """``python -m prg.tracking move-store mlruns.db /old/checkout/mlartifacts mlartifacts``, or
    ``python -m prg.tracking log-pending logs/pending-runs/write-....json``: log a run that a
    command handed to the background (:func:`prg.tracking.task_run`), again after a failure."""
    moving = argv[:1] == ["move-store"] and len(argv) == 4
    if not moving and not (argv[:1] == ["log-pending"] and len(argv) == 2):
        print(f"prg.tracking: error: usage: {USAGE}", file=sys.stderr)
        return 2
    try:
        if not moving:
            os.nice(10)  # behind the commands the user is waiting for
            stamp = time.strftime("%Y-%m-%d %H:%M:%S")
            try:
                run_id = log_pending_run(argv[1])
            except UsageError:
                raise
            except Exception as err:  # the store or an artifact: the file is kept for a retry
                print(
                    f"prg.tracking: error: {stamp} pending run {argv[1]} not logged"
                    f" ({type(err).__name__}: {err}); the file is kept: run"
                    f" `python -m prg.tracking log-pending {argv[1]}` again",
                    file=sys.stderr,
                )
                return 1
            print(f"{stamp} logged run {run_id} from {argv[1]}")
            return 0
        changed = move_store(*argv[1:])
    except UsageError as err:
        print(f"prg.tracking: error: {err}", file=sys.stderr)
        return 2
    print(f"{changed} artifact locations now under {Path(argv[3]).resolve()}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
