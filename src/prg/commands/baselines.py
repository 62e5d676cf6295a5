"""``python -m prg.commands.baselines parent|evaluate|aggregate DIR``: the steps of ``make
baselines`` around its training sweep (families x seeds, quick profile), each safe to rerun.

Layout under ``DIR`` (``baselines/``, ignored by git)::

    parent.json                          the sweep's MLflow parent run (id, store)
    starts.json                          each start of the command: when it started and ended
    checkpoints/<family>-seed<s>/        prg-train's checkpoint_dir
    seed<s>/<family>/model.ckpt          prg-train's export_dir (+ metrics.json, history.csv)
    seed<s>/reports/<family>/            prg-evaluate's report_dir (+ timing.json: its CPU and
                                         wall time)
    classifiers/                         the coherence classifiers, trained once, shared by seeds
    report/                              the aggregate: <table>.md/.csv, comparisons.csv,
                                         index.md, aggregate.json, comparison.png

- ``parent DIR [--started EPOCH] [OVERRIDES]``: record the start in ``starts.json``, open the
  sweep's parent run in the training experiment (or reuse
  the one ``parent.json`` names, when it is in this store) and print its id, for
  ``PRG_PARENT_RUN_ID`` of the ``prg-train -m`` sweep (whose jobs become its children);
- ``evaluate DIR --families F --seeds S [OVERRIDES]``: one ``prg-evaluate`` per (seed, family),
  with the demo's importance-sampling budget (``params.yaml`` ``evaluate:``), parts likelihood,
  coherence (with roughness and robustness) and likeness, the evaluation seed the training seed,
  each run a child of the parent; skipped where its metrics.json is newer than the model;
- ``aggregate DIR [--families F --seeds S] [--started EPOCH] [OVERRIDES]``: the reports over
  seeds (:mod:`prg.evaluation.seeds`) into ``DIR/report/``, their metrics
  (``<family>/<metric>/mean``, ``/ci_low``, ``/ci_high``) and files into the parent run, which
  is then finished; the wall time is summed over the command's starts (``starts.json``);
- ``stopped DIR --started EPOCH``: record the end of a start that did not reach ``aggregate``
  (``make baselines`` runs it on exit: Ctrl-C, a kill, a failed step).

``OVERRIDES`` are Hydra overrides of ``prg-evaluate`` (``evaluate``; they win over the
defaults above) or of the store's config (``paths.root_dir=...``, ``logger.tracking_uri=...``).
Bad input: one line, exit 2.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from prg.errors import UsageError, UsageParser
from prg.files import read_json, staged_outputs, write_json, write_text
from prg.resources import cpu_name

PROG = "python -m prg.commands.baselines"
PARTS = "[likelihood,coherence,likeness]"
PARENT_FILE = "parent.json"
STARTS_FILE = "starts.json"


# ---- arguments -------------------------------------------------------------------------------
def names(text: str) -> list[str]:
    """``"cvae avae_ts"`` or ``"cvae,avae_ts"`` -> the names, in order, once each."""
    found = [n for n in text.replace(",", " ").split() if n]
    if not found:
        raise UsageError("--families: give at least one family, e.g. --families cvae,avae_ts")
    return list(dict.fromkeys(found))


def seed_list(text: str) -> list[int]:
    """``"0,1,2"`` or ``"0 1 2"`` -> the seeds (non-negative integers)."""
    parts = [p for p in text.replace(",", " ").split() if p]
    if not parts or not all(p.isdigit() for p in parts):
        raise UsageError(f"--seeds: expected non-negative integers such as 0,1,2, got {text!r}")
    return list(dict.fromkeys(int(p) for p in parts))


def _config(overrides: Sequence[str]) -> Any:
    """The train config (store, experiments, paths) with the overrides that concern it."""
    from prg.commands.cli import compose_config

    mine = [
        o for o in overrides if o.split("=", 1)[0].lstrip("+~").startswith(("paths.", "logger."))
    ]
    return compose_config("train", mine)


# ---- the parent run --------------------------------------------------------------------------
def open_parent(folder: Path, overrides: Sequence[str], command: str = "make baselines") -> str:
    """The id of the sweep's parent run: the one ``folder/parent.json`` names when it is in this
    store, else a new one in the training experiment (recorded in ``parent.json``)."""
    from mlflow.exceptions import MlflowException

    from prg.tracking import DESCRIPTION_TAG, experiment_of, mlflow_client, tracking_uri

    cfg = _config(overrides)
    uri = tracking_uri(cfg.logger.get("tracking_uri"), cfg.paths.root_dir)
    client = mlflow_client(uri)
    recorded = folder / PARENT_FILE
    if recorded.is_file():
        known = read_json(recorded, "parent run file")
        if known.get("tracking_uri") == uri:
            try:
                run = client.get_run(known["run_id"])
                if run.info.lifecycle_stage == "active":
                    if run.info.status != "RUNNING":  # a rerun: open again until aggregated
                        client.update_run(run.info.run_id, status="RUNNING")
                    return run.info.run_id
            except (MlflowException, KeyError):
                pass
    experiment = experiment_of(client, cfg, tasks=False)
    run = client.create_run(
        experiment,
        run_name=f"baselines {time.strftime('%Y-%m-%d %H:%M:%S')}",
        tags={
            "prg.sweep": "parent",
            "prg.baselines": str(folder.resolve()),
            DESCRIPTION_TAG: (
                "Baselines over seeds: each (family, seed) training run is a child; the "
                "aggregated metrics (`<family>/<metric>/mean`, `/ci_low`, `/ci_high`) and the "
                f"comparison figure are here.  \nCommand: `{command}`; reports in "
                f"`{folder}/report/`"
            ),
        },
    )
    write_json(
        recorded, {"run_id": run.info.run_id, "tracking_uri": uri, "experiment_id": experiment}
    )
    return run.info.run_id


def log_to_parent(run_id: str, agg: dict, report: Path, overrides: Sequence[str]) -> None:
    """The aggregate's metrics and the report folder into the parent run, then finish it."""
    from mlflow.entities import Metric

    from prg.tracking import mlflow_client, tracking_uri

    cfg = _config(overrides)
    client = mlflow_client(tracking_uri(cfg.logger.get("tracking_uri"), cfg.paths.root_dir))
    now = int(time.time() * 1000)
    metrics = []
    for family, table in agg["summaries"].items():
        for metric, s in table.items():
            for key in ("mean", "ci_low", "ci_high"):
                value = s.get(key)
                if value is not None and value == value:
                    metrics.append(Metric(f"{family}/{metric}/{key}", float(value), now, 0))
            metrics.append(Metric(f"{family}/{metric}/n", float(s["n"]), now, 0))
    for c in agg["comparisons"]:
        if c["p_holm"] is not None and c["p_holm"] == c["p_holm"]:
            name = f"compare/{c['metric']}/{c['a']}-{c['b']}/p_holm"
            metrics.append(Metric(name, float(c["p_holm"]), now, 0))
    if agg.get("wall_min") is not None:
        metrics.append(Metric("sweep/wall_min", float(agg["wall_min"]), now, 0))
    for start in range(0, len(metrics), 1000):  # MLflow takes at most 1000 a batch
        client.log_batch(run_id, metrics=metrics[start : start + 1000])
    client.set_tag(run_id, "prg.seeds", " ".join(map(str, agg["seeds"])))
    client.set_tag(run_id, "prg.families", " ".join(agg["families"]))
    client.log_artifacts(run_id, str(report), "report")
    client.set_terminated(run_id)


# ---- the command's starts ----------------------------------------------------------------
# A sweep stopped and run again is one piece of work done in several starts: its wall time is
# the sum of the starts' durations, the time between them (nothing running) left out.
def read_starts(folder: Path) -> list[dict]:
    """The recorded starts of the command on ``folder`` (``starts.json``), oldest first."""
    path = folder / STARTS_FILE
    return read_json(path, "starts file")["starts"] if path.is_file() else []


def record_start(folder: Path, started: float) -> None:
    """Add the start at ``started`` (epoch seconds) unless it is recorded."""
    starts = read_starts(folder)
    if not any(s["started"] == started for s in starts):
        starts.append({"started": started, "ended": None, "how": None})
        write_json(folder / STARTS_FILE, {"starts": starts})


def record_end(folder: Path, started: float, ended: float, how: str) -> None:
    """End the start at ``started`` (added when missing) at ``ended``; ``how`` is "aggregated"
    or "stopped". A start already ended keeps its record (the exit after a finished
    aggregation is not a stop)."""
    starts = read_starts(folder)
    entry = next((s for s in starts if s["started"] == started), None)
    if entry is None:
        entry = {"started": started, "ended": None, "how": None}
        starts.append(entry)
    if entry["ended"] is None:
        entry.update(ended=ended, how=how)
        write_json(folder / STARTS_FILE, {"starts": sorted(starts, key=lambda s: s["started"])})


def wall_over_starts(starts: Sequence[dict]) -> tuple[float, int, int]:
    """(minutes summed over the ended starts, starts, starts without a recorded end)."""
    ended = [s for s in starts if s["ended"] is not None]
    minutes = sum(s["ended"] - s["started"] for s in ended) / 60
    return minutes, len(starts), len(starts) - len(ended)


def wall_sentence(minutes: float, n_starts: int, unrecorded: int, machine: str) -> str:
    """The report's line on how long the command took."""
    text = f"`make baselines` took {minutes:.1f} min wall on {machine}"
    if n_starts > 1:
        text += f", summed over its {n_starts} starts (stopped and run again)"
    if unrecorded:
        text += f"; {unrecorded} start(s) killed without a recorded end are not counted"
    return text + "."


# ---- evaluation ------------------------------------------------------------------------------
def evaluation_budget(root: Path) -> dict[str, str]:
    """The demo's importance-sampling budget (``params.yaml`` ``evaluate:``) as overrides."""
    import yaml

    params = root / "params.yaml"
    budget = (
        (yaml.safe_load(params.read_text()) or {}).get("evaluate", {}) if params.is_file() else {}
    )
    keys = {
        "k_marginal": "likelihood.k_marginal",
        "k_conditional": "likelihood.k_conditional",
        "n_test": "likelihood.n_test",
    }
    return {keys[k]: "null" if v is None else str(v) for k, v in budget.items() if k in keys}


def evaluate_overrides(
    folder: Path, family: str, seed: int, root: Path, extra: Sequence[str]
) -> list[str]:
    """The ``prg-evaluate`` overrides of one (seed, family); ``extra`` win."""
    from prg.evaluation.seeds import evaluation_dir

    chosen = {
        "families": f"[{family}]",
        "models_dir": str((folder / f"seed{seed}").resolve()),
        "report_dir": str(evaluation_dir(folder, seed, family).resolve()),
        "seed": str(seed),
        "parts": PARTS,
        "progress": "false",
        "figures": "false",
        "run_name": f"evaluate-{family}-seed{seed}",
        "classifier.dir": str((folder / "classifiers").resolve()),
        "classifier.seed": "0",  # one judge for every seed
        **evaluation_budget(root),
    }
    for override in extra:
        key, _, value = override.partition("=")
        chosen[key] = value
    return [f"{k}={v}" for k, v in chosen.items()]


def up_to_date(folder: Path, seed: int, family: str) -> bool:
    """Whether the (seed, family) evaluation and its timing are newer than its model."""
    from prg.evaluation.seeds import evaluation_dir

    model = folder / f"seed{seed}" / family / "model.ckpt"
    done = evaluation_dir(folder, seed, family)
    files = [done / "metrics.json", done / "timing.json"]
    return (
        all(f.is_file() for f in files)
        and min(f.stat().st_mtime for f in files) >= model.stat().st_mtime
    )


def _command(name: str) -> str:
    here = Path(sys.executable).parent / name
    return str(here) if here.is_file() else (shutil.which(name) or name)


def check_trained(folder: Path, families: list[str], seeds: list[int]) -> None:
    """Refuse, naming the first, a (seed, family) with no exported model."""
    for seed in seeds:
        for family in families:
            model = folder / f"seed{seed}" / family / "model.ckpt"
            if not model.is_file():
                raise UsageError(f"{model} does not exist: train the sweep first (make baselines)")


def evaluate(
    folder: Path,
    families: list[str],
    seeds: list[int],
    extra: Sequence[str],
    parent: str | None,
    root: Path,
    jobs: int = 1,
) -> list[tuple[int, str, str]]:
    """Run ``prg-evaluate`` for each (seed, family) not up to date, ``jobs`` at a time;
    (seed, family, what) each. A failed evaluation lets the running ones finish, starts no
    more, and exits with its code."""
    from prg.evaluation.seeds import evaluation_dir

    check_trained(folder, families, seeds)
    env = {**os.environ, **({"PRG_PARENT_RUN_ID": parent} if parent else {})}
    done = []
    if not all(up_to_date(folder, s, f) for s in seeds for f in families):
        # the classifiers first (reused while their data and settings hold), so that no
        # family's evaluation time includes training them
        args = evaluate_overrides(folder, families[0], seeds[0], root, extra)
        args = [a for a in args if not a.startswith("parts=")] + ["parts=[classifiers]"]
        code = subprocess.run([_command("prg-evaluate"), *args], env=env).returncode
        if code:
            raise SystemExit(code)
    pending = []
    for seed in seeds:
        for family in families:
            if up_to_date(folder, seed, family):
                done.append((seed, family, "up to date"))
            else:
                pending.append((seed, family))
    if jobs > 1:  # each evaluation one share of the cores, unless the caller chose
        env.setdefault("OMP_NUM_THREADS", str(max(1, (os.cpu_count() or 1) // jobs)))
    # the Popen objects stay referenced until their child is reaped here: a dropped one is
    # polled (reaped) by the next Popen's clean-up, and os.wait4 would never see that child
    running: dict[int, tuple[int, str, float, subprocess.Popen]] = {}
    failed = 0
    while pending or running:
        while pending and len(running) < jobs and not failed:
            seed, family = pending.pop(0)
            args = evaluate_overrides(folder, family, seed, root, extra)
            child = subprocess.Popen([_command("prg-evaluate"), *args], env=env)
            running[child.pid] = (seed, family, time.perf_counter(), child)
        if not running:
            break
        # wait4, not Popen.wait: the finished child's own CPU time, whatever else runs
        pid, status, usage = os.wait4(-1, 0)
        if pid not in running:
            continue
        seed, family, start, child = running.pop(pid)
        wall = time.perf_counter() - start
        code = child.returncode = os.waitstatus_to_exitcode(status)
        if code:
            failed = failed or code
            continue
        cpu = usage.ru_utime + usage.ru_stime
        write_json(
            evaluation_dir(folder, seed, family) / "timing.json",
            {"cpu_s": round(cpu, 2), "wall_s": round(wall, 2), "jobs": jobs},
        )
        print(f"seed {seed} {family}: evaluated in {wall / 60:.1f} min ({cpu / 60:.1f} CPU)")
        done.append((seed, family, "evaluated"))
    if failed:
        raise SystemExit(failed)
    return done


# ---- aggregation -----------------------------------------------------------------------------
def aggregate(
    folder: Path,
    families: list[str] | None,
    seeds: list[int] | None,
    started: float | None,
    overrides: Sequence[str],
    log: bool = True,
) -> dict:
    """Write ``folder/report/`` from the sweep's metrics and log it into the parent run."""
    from prg.evaluation import seed_report
    from prg.evaluation import seeds as over_seeds

    values = over_seeds.collect(folder, families, seeds)
    agg = over_seeds.aggregate(values)
    agg["machine"] = cpu_name()
    wall = ""
    if started is not None:
        record_end(folder, started, time.time(), "aggregated")
    starts = read_starts(folder)
    if starts:  # an aggregation by hand after the sweep keeps its wall time
        minutes, n_starts, unrecorded = wall_over_starts(starts)
        agg["wall_min"] = round(minutes, 1)
        agg["starts"] = n_starts
        wall = wall_sentence(minutes, n_starts, unrecorded, agg["machine"])
    report = folder / "report"
    with staged_outputs(report) as staging:
        for name, text in seed_report.report_texts(agg, wall).items():
            write_text(staging / name, text, atomic=False)
        seed_report.comparison_figure(agg, staging / "comparison.png")
    if log:
        run_id = open_parent(folder, overrides)
        log_to_parent(run_id, over_seeds.json_ready(agg), report, overrides)
    return agg


# ---- the command line ------------------------------------------------------------------------
def main(argv: list[str] | None = None) -> int:
    parser = UsageParser(prog=PROG, description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="step", required=True)
    p = sub.add_parser("parent", help="open (or reuse) the sweep's parent run; print its id")
    e = sub.add_parser("evaluate", help="prg-evaluate each (seed, family) not up to date")
    a = sub.add_parser("aggregate", help="reports over seeds into DIR/report and the parent run")
    x = sub.add_parser("stopped", help="record the end of a start that did not aggregate")
    for s in (p, e, a, x):
        s.add_argument("dir", type=Path, help="the sweep's folder (baselines)")
        s.add_argument("overrides", nargs="*", help="Hydra overrides (key=value), anywhere")
    e.add_argument("--families", required=True, help="e.g. cvae,avae_ts")
    e.add_argument("--seeds", required=True, help="e.g. 0,1,2,3,4")
    e.add_argument("--jobs", default="1", help="evaluations at once (default 1)")
    a.add_argument("--families", default=None, help="default: every family evaluated")
    a.add_argument("--seeds", default=None, help="default: every seed<s> folder")
    for s in (p, a):
        s.add_argument("--started", type=float, default=None, help="this start (epoch s)")
    x.add_argument("--started", type=float, required=True, help="this start (epoch s)")
    a.add_argument("--no-mlflow", action="store_true", help="write the reports only")
    try:
        args, rest = parser.parse_known_args(argv)  # overrides may follow the options too
        args.overrides = [*args.overrides, *rest]
        bad = [o for o in args.overrides if "=" not in o or o.startswith("-")]
        if bad:
            raise UsageError(f"expected Hydra overrides key=value, got {bad[0]!r}")
        if args.step == "parent":
            if args.started is not None:
                record_start(args.dir, args.started)
            print(open_parent(args.dir, args.overrides))
        elif args.step == "stopped":
            record_end(args.dir, args.started, time.time(), "stopped")
        elif args.step == "evaluate":
            from prg.commands.cli import project_root

            families, seeds = names(args.families), seed_list(args.seeds)
            if not args.jobs.isdigit() or int(args.jobs) < 1:
                raise UsageError(f"--jobs {args.jobs!r}: expected a whole number of at least 1")
            check_trained(args.dir, families, seeds)
            parent = open_parent(args.dir, args.overrides)
            root = next(
                (
                    Path(o.split("=", 1)[1])
                    for o in args.overrides
                    if o.startswith("paths.root_dir=")
                ),
                project_root()[0],
            )
            evaluate(args.dir, families, seeds, args.overrides, parent, root, int(args.jobs))
        else:
            families = names(args.families) if args.families else None
            seeds = seed_list(args.seeds) if args.seeds else None
            agg = aggregate(
                args.dir, families, seeds, args.started, args.overrides, log=not args.no_mlflow
            )
            print(
                f"{args.dir / 'report'}: {len(set(agg['families']) - {'real'})} families, seeds "
                f"{' '.join(map(str, agg['seeds']))}"
            )
    except UsageError as err:
        print(f"{PROG}: error: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
