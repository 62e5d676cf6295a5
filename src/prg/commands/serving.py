"""``python -m prg.commands.serving register EXPORT_DIR [--evaluation JSON]``: register a trained
model (its run's logged MLflow model, :mod:`prg.serving`) as ``prg-<family>`` with its metrics and
move the ``champion`` alias (README "Serving a trained model"; ``make demo`` runs it)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from prg.commands.cli import project_root
from prg.errors import UsageError, UsageParser
from prg.serving import register_version
from prg.tracking import tracking_uri

PROG = "python -m prg.commands.serving"


def main(argv: list[str] | None = None) -> int:
    """``python -m prg.commands.serving register EXPORT_DIR [--evaluation JSON]``: register the model
    exported to ``EXPORT_DIR`` (``models/<family>``: its ``metrics.json`` names the run) as
    ``prg-<family>`` with its training metrics and, given the evaluation's ``metrics.json``
    (``reports/metrics.json``), its coherence and Table I cells."""

    parser = UsageParser(prog=PROG, description=main.__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    reg = sub.add_parser("register", help="register an exported model with its metrics")
    reg.add_argument("export_dir", type=Path)
    reg.add_argument("--evaluation", type=Path, default=None, help="prg-evaluate's metrics.json")
    reg.add_argument("--name", default=None, help="registered model name (default prg-<family>)")
    reg.add_argument(
        "--tracking-uri",
        default=None,
        help="default: MLFLOW_TRACKING_URI, else the project's mlruns.db",
    )
    try:
        args = parser.parse_args(argv)
        exported = _read_json(args.export_dir / "metrics.json")
        family, run_id = exported.get("family"), exported.get("mlflow_run_id")
        if not isinstance(family, str) or not isinstance(run_id, str):
            raise UsageError(
                f"{args.export_dir / 'metrics.json'}: expected the family and mlflow_run_id "
                "of a prg-train export (export_dir=...)"
            )
        metrics = {k: v for k, v in exported.items() if isinstance(v, int | float)}
        if args.evaluation is not None:
            evaluated = _read_json(args.evaluation)
            evaluated = evaluated.get("metrics", evaluated)
            prefix = f"{family}/"
            metrics.update(
                {k.removeprefix(prefix): v for k, v in evaluated.items() if k.startswith(prefix)}
            )
        uri = args.tracking_uri or tracking_uri(None, project_root()[0])
        name = args.name or f"prg-{family}"
        version = register_version(name, run_id, uri, metrics)
    except UsageError as err:
        print(f"{PROG}: {err}")
        return 2
    print(f"registered {name} version {version} (models:/{name}/{version})")
    return 0


def _read_json(path: Path) -> dict:
    try:
        value = json.loads(path.read_text())
    except FileNotFoundError:
        raise UsageError(f"{path} does not exist") from None
    except (OSError, ValueError) as err:
        raise UsageError(f"{path} is not readable JSON ({err})") from None
    if not isinstance(value, dict):
        raise UsageError(f"{path}: expected a JSON object")
    return value


if __name__ == "__main__":
    sys.exit(main())
