"""Tests of ``prg.commands.baselines`` (``make baselines``' steps): arguments, the evaluation's
overrides and its skip rule, the parent run read back from a real SQLite store, bad input; and
(slow) the whole ``make baselines`` on a tiny budget."""

from __future__ import annotations

import json
import os
import subprocess
import time

import pytest

from prg.commands import baselines
from prg.errors import UsageError
from prg.evaluation import seeds
from prg.files import write_json
from prg.tracking import mlflow_client, sqlite_uri
from tests.conftest import REPO
from tests.helpers.seeds import seed_sweep


def test_names_and_seeds_take_commas_or_spaces():
    assert baselines.names("cvae avae_ts,muse cvae") == ["cvae", "avae_ts", "muse"]
    assert baselines.seed_list("0,1 2") == [0, 1, 2]
    with pytest.raises(UsageError, match="--seeds"):
        baselines.seed_list("0,one")
    with pytest.raises(UsageError, match="--families"):
        baselines.names(" , ")


def test_evaluation_overrides_take_the_demo_budget_and_give_way_to_the_callers(tmp_path):
    (tmp_path / "params.yaml").write_text(
        "seed: 0\nevaluate:\n  k_marginal: 100\n  k_conditional: 200\n  n_test: null\n"
    )
    args = baselines.evaluate_overrides(
        tmp_path / "b", "cvae", 3, tmp_path, ["likelihood.k_marginal=7", "paths.data_dir=/d"]
    )
    assert "likelihood.k_marginal=7" in args and "likelihood.k_marginal=100" not in args
    assert {
        "likelihood.k_conditional=200",
        "likelihood.n_test=null",
        "seed=3",
        "families=[cvae]",
        "parts=[likelihood,coherence,likeness]",
        "classifier.seed=0",
        "paths.data_dir=/d",
    } <= set(args)
    assert f"report_dir={(tmp_path / 'b' / 'seed3' / 'reports' / 'cvae').resolve()}" in args
    assert f"models_dir={(tmp_path / 'b' / 'seed3').resolve()}" in args


def test_an_evaluation_newer_than_its_model_is_up_to_date(tmp_path):
    root = seed_sweep(tmp_path, ["cvae"], [0])
    model = root / "seed0" / "cvae" / "model.ckpt"
    model.write_bytes(b"x")
    done = seeds.evaluation_dir(root, 0, "cvae")
    past = time.time() - 100
    os.utime(model, (past, past))
    assert baselines.up_to_date(root, 0, "cvae")
    os.utime(done / "metrics.json", (past - 10, past - 10))  # the model was retrained since
    assert not baselines.up_to_date(root, 0, "cvae")
    os.utime(done / "metrics.json", (past + 10, past + 10))
    (done / "timing.json").unlink()  # an evaluation that stopped before its timing
    assert not baselines.up_to_date(root, 0, "cvae")


def test_evaluate_refuses_a_sweep_that_was_not_trained(tmp_path, capsys):
    code = baselines.main(
        [
            "evaluate",
            str(tmp_path / "b"),
            "--families",
            "cvae",
            "--seeds",
            "0",
            f"paths.root_dir={tmp_path}",
        ]
    )
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "seed0/cvae/model.ckpt does not exist" in err[0]


# A stand-in for prg-evaluate (the real one is run by the slow end-to-end test): it records when
# it ran, burns a known amount of CPU, writes metrics.json into its report_dir, and fails for the
# family named in FAIL_FAMILY.
_STAND_IN = """#!{python}
import json, os, sys, time
args = dict(a.split("=", 1) for a in sys.argv[1:])
if args.get("parts") == "[classifiers]":
    sys.exit(0)
start = time.time()
end = time.process_time() + 0.3
while time.process_time() < end:
    pass
time.sleep(0.5)
if args["families"] == "[" + os.environ.get("FAIL_FAMILY", "") + "]":
    sys.exit(3)
os.makedirs(args["report_dir"], exist_ok=True)
with open(os.path.join(args["report_dir"], "metrics.json"), "w") as f:
    json.dump({{"start": start, "end": time.time(), "threads": os.environ["OMP_NUM_THREADS"]}}, f)
"""


def _stand_in_sweep(tmp_path, monkeypatch, families, seed_ids):
    import sys

    program = tmp_path / "prg-evaluate"
    program.write_text(_STAND_IN.format(python=sys.executable))
    program.chmod(0o755)
    monkeypatch.setattr(baselines, "_command", lambda name: str(program))
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    root = tmp_path / "b"
    for s in seed_ids:
        for f in families:
            (root / f"seed{s}" / f).mkdir(parents=True)
            (root / f"seed{s}" / f / "model.ckpt").write_bytes(b"x")
    return root


def test_evaluations_run_jobs_at_a_time_each_timed_by_its_own_cpu(tmp_path, monkeypatch):
    root = _stand_in_sweep(tmp_path, monkeypatch, ["cvae", "muse"], [0, 1])
    done = baselines.evaluate(root, ["cvae", "muse"], [0, 1], [], None, tmp_path, jobs=2)
    assert sorted(done) == [(s, f, "evaluated") for s in (0, 1) for f in ("cvae", "muse")]
    runs = []
    for s in (0, 1):
        for f in ("cvae", "muse"):
            where = seeds.evaluation_dir(root, s, f)
            metrics = json.loads((where / "metrics.json").read_text())
            timing = json.loads((where / "timing.json").read_text())
            runs.append((metrics["start"], metrics["end"]))
            # its own CPU (about 0.3 s of spinning), not its neighbour's too
            assert 0.25 <= timing["cpu_s"] < 0.55 and timing["wall_s"] >= 0.75
            assert timing["jobs"] == 2 and metrics["threads"] == str(max(1, os.cpu_count() // 2))
    runs.sort()
    assert all(later[0] < earlier[1] for earlier, later in zip(runs[::2], runs[1::2]))  # overlap
    assert baselines.evaluate(root, ["cvae", "muse"], [0, 1], [], None, tmp_path, jobs=2) == [
        (s, f, "up to date") for s in (0, 1) for f in ("cvae", "muse")
    ]


def test_a_child_that_ends_while_the_next_starts_is_still_waited_for(tmp_path, monkeypatch):
    # each start takes longer than an evaluation: the previous child has ended by the time the
    # scheduler moves on, and a Popen it no longer held would reap it behind os.wait4's back
    import subprocess

    class SlowStart(subprocess.Popen):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            time.sleep(1.2)

    root = _stand_in_sweep(tmp_path, monkeypatch, ["cvae", "muse"], [0, 1])
    monkeypatch.setattr(baselines.subprocess, "Popen", SlowStart)
    done = baselines.evaluate(root, ["cvae", "muse"], [0, 1], [], None, tmp_path, jobs=2)
    assert sorted(done) == [(s, f, "evaluated") for s in (0, 1) for f in ("cvae", "muse")]


def test_a_failed_evaluation_lets_the_running_one_finish_and_starts_no_more(tmp_path, monkeypatch):
    root = _stand_in_sweep(tmp_path, monkeypatch, ["cvae", "muse"], [0, 1, 2])
    monkeypatch.setenv("FAIL_FAMILY", "cvae")
    with pytest.raises(SystemExit) as stopped:
        baselines.evaluate(root, ["cvae", "muse"], [0, 1, 2], [], None, tmp_path, jobs=2)
    assert stopped.value.code == 3
    # seed 0: cvae failed beside muse, which finished; nothing after them was started
    assert (seeds.evaluation_dir(root, 0, "muse") / "timing.json").is_file()
    assert not any((seeds.evaluation_dir(root, s, "muse")).exists() for s in (1, 2))


@pytest.mark.parametrize(
    "argv, expected",
    [
        (["aggregate", "{b}", "--seeds", "x"], "--seeds"),
        (["aggregate", "{b}", "notanoverride"], "key=value"),
        (["aggregate", "{b}", "--families", "cvae", "--seeds", "7", "--no-mlflow"], "seed7"),
        (["evaluate", "{b}", "--families", "cvae", "--seeds", "0", "--jobs", "0"], "--jobs"),
        (["evaluate", "{b}", "--seeds", "0"], "--families"),  # argparse's own checks too
        (["stopped", "{b}"], "--started"),
        (["stopped", "{b}", "--started", "noon"], "'noon'"),
        (["restart", "{b}"], "restart"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, argv, expected):
    seed_sweep(tmp_path / "b", ["cvae"], [0])
    assert baselines.main([a.format(b=tmp_path / "b") for a in argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and expected in err[0] and err[0].startswith(baselines.PROG)


def test_the_parent_run_holds_the_aggregate_read_back_from_the_store(tmp_path, monkeypatch):
    monkeypatch.delenv("MLFLOW_TRACKING_URI", raising=False)
    monkeypatch.delenv("PRG_PARENT_RUN_ID", raising=False)
    root = seed_sweep(tmp_path / "b")
    overrides = [f"paths.root_dir={tmp_path}"]
    parent = baselines.open_parent(root, overrides)
    assert baselines.open_parent(root, overrides) == parent  # a rerun reuses it
    agg = baselines.aggregate(root, None, None, time.time() - 90, overrides)
    client = mlflow_client(sqlite_uri(tmp_path / "mlruns.db"))
    run = client.get_run(parent)
    assert run.info.status == "FINISHED" and run.data.tags["prg.sweep"] == "parent"
    assert run.info.experiment_id == client.get_experiment_by_name("prg").experiment_id
    summary = agg["summaries"]["avae_ts"]["coherence_T_given_S"]
    metrics = run.data.metrics
    for key in ("mean", "ci_low", "ci_high"):
        assert metrics[f"avae_ts/coherence_T_given_S/{key}"] == pytest.approx(summary[key])
    assert metrics["avae_ts/coherence_T_given_S/n"] == 3
    assert "cvae/train_cpu_min/mean" in metrics and metrics["sweep/wall_min"] >= 1.5
    assert any(k.startswith("compare/coherence_T_given_S/cvae-avae_ts") for k in metrics)
    names = {a.path for a in client.list_artifacts(parent, "report")}
    assert {"report/comparison.png", "report/aggregate.json", "report/coherence.md"} <= names
    report = json.loads((root / "report" / "aggregate.json").read_text())
    assert report["seeds"] == [0, 1, 2] and report["wall_min"] >= 1.5
    assert "took" in (root / "report" / "index.md").read_text()
    # a second aggregation: the same parent, open again and finished again, no second parent
    baselines.aggregate(root, None, None, None, overrides)
    runs = client.search_runs([run.info.experiment_id])
    assert [r.info.run_id for r in runs] == [parent]


def test_a_recorded_parent_from_another_store_is_not_reused(tmp_path, monkeypatch):
    monkeypatch.delenv("MLFLOW_TRACKING_URI", raising=False)
    root = tmp_path / "b"
    write_json(root / baselines.PARENT_FILE, {"run_id": "abc", "tracking_uri": "sqlite:///x.db"})
    parent = baselines.open_parent(root, [f"paths.root_dir={tmp_path}"])
    assert parent != "abc"
    assert json.loads((root / baselines.PARENT_FILE).read_text())["run_id"] == parent


def test_the_wall_time_of_a_resumed_sweep_sums_its_starts_not_the_gaps(tmp_path):
    root = seed_sweep(tmp_path / "b")
    now = time.time()
    first, second = now - 3600, now - 600  # 30 min of work, a 20-min gap, then this start
    baselines.record_start(root, first)
    baselines.record_start(root, first)  # recorded once
    baselines.record_end(root, first, first + 1800, "stopped")
    baselines.record_start(root, second)
    agg = baselines.aggregate(root, None, None, second, [], log=False)
    assert agg["starts"] == 2 and agg["wall_min"] == pytest.approx(30 + 10, abs=0.2)
    starts = baselines.read_starts(root)
    assert [s["how"] for s in starts] == ["stopped", "aggregated"]
    # the exit after a finished aggregation is not a stop: the record stays
    baselines.record_end(root, second, time.time() + 999, "stopped")
    assert baselines.read_starts(root) == starts
    assert "over its 2 starts" in (root / "report" / "index.md").read_text()
    # aggregated again by hand (no start of its own): the same wall time
    again = baselines.aggregate(root, None, None, None, [], log=False)
    assert again["wall_min"] == agg["wall_min"] and baselines.read_starts(root) == starts


def test_a_start_killed_without_a_record_of_its_end_is_named_not_counted():
    starts = [
        {"started": 0.0, "ended": 600.0, "how": "stopped"},
        {"started": 700.0, "ended": None, "how": None},
        {"started": 900.0, "ended": 1500.0, "how": "aggregated"},
    ]
    minutes, n_starts, unrecorded = baselines.wall_over_starts(starts)
    assert (minutes, n_starts, unrecorded) == (20.0, 3, 1)
    text = baselines.wall_sentence(minutes, n_starts, unrecorded, "a CPU")
    assert "20.0 min" in text and "3 starts" in text and "1 start(s) killed" in text
    assert "starts" not in baselines.wall_sentence(5.0, 1, 0, "a CPU")


def test_make_baselines_records_the_end_of_a_start_that_fails(tmp_path, small_dataset):
    """A training step that fails (here: a bad override) ends the command; its exit records
    the start's end, so a later run's wall time counts this start's minutes."""
    out = tmp_path / "baselines"
    env = {**os.environ, "PRG_ROOT": str(tmp_path)}
    env.pop("MLFLOW_TRACKING_URI", None)
    env.pop("PRG_PARENT_RUN_ID", None)
    make = [
        "make", "-s", "-o", "setup", "baselines", f"BASELINES={out}",
        "BASELINE_SEEDS=0", "BASELINE_FAMILIES=cvae", f"BASELINE_ARGS=paths.data_dir={small_dataset}",
        "BASELINE_TRAIN_ARGS=trainer.max_epochs=many",
    ]  # fmt: skip
    before = time.time()
    result = subprocess.run(make, cwd=REPO, env=env, capture_output=True, text=True, timeout=300)
    assert result.returncode != 0
    [start] = baselines.read_starts(out)
    assert start["how"] == "stopped" and before - 1 <= start["started"] <= start["ended"]
    assert start["ended"] <= time.time()


@pytest.mark.slow
def test_make_baselines_end_to_end_on_a_tiny_budget(tmp_path, small_dataset):
    """Two families, two seeds, a few batches: training under one parent, evaluation per
    (seed, family) as children, the aggregate in the parent run; a rerun skips evaluation."""
    out = tmp_path / "baselines"
    env = {**os.environ, "PRG_ROOT": str(tmp_path)}
    env.pop("MLFLOW_TRACKING_URI", None)
    env.pop("PRG_PARENT_RUN_ID", None)
    make = [
        "make",
        "-s",
        "-o",
        "setup",
        "baselines",
        f"BASELINES={out}",
        "BASELINE_SEEDS=0,1",
        "BASELINE_FAMILIES=cvae avae_ts",
        f"BASELINE_ARGS=paths.data_dir={small_dataset}",
        "BASELINE_TRAIN_ARGS=trainer.max_epochs=1 trainer.limit_train_batches=3 "
        "trainer.limit_val_batches=2 ~callbacks.figures",
        "BASELINE_EVAL_ARGS=likelihood.k_marginal=5 likelihood.k_conditional=5 "
        "likelihood.n_test=8 n_test=40 classifier.epochs=1 likeness.n_per_class=4 "
        "coherence.impute_steps=0",
    ]
    result = subprocess.run(make, cwd=REPO, env=env, capture_output=True, text=True, timeout=1500)
    assert result.returncode == 0, (result.stdout + result.stderr)[-4000:]
    report = json.loads((out / "report" / "aggregate.json").read_text())
    assert report["families"] == ["cvae", "avae_ts"] and report["seeds"] == [0, 1]
    assert report["summaries"]["cvae"]["coherence_T_given_S"]["n"] == 2
    assert report["tables"]["table1"] and report["tables"]["robustness"]
    assert report["wall_min"] > 0
    for name in (
        "coherence.md",
        "robustness.md",
        "table1.md",
        "likeness.md",
        "roughness.md",
        "timing.md",
        "comparisons.csv",
        "comparison.png",
    ):
        assert (out / "report" / name).is_file(), name
    client = mlflow_client(sqlite_uri(tmp_path / "mlruns.db"))
    parent = json.loads((out / baselines.PARENT_FILE).read_text())["run_id"]
    training = client.search_runs([client.get_experiment_by_name("prg").experiment_id])
    children = [r for r in training if r.info.run_id != parent]
    assert {(r.data.tags["prg.family"], r.data.tags["prg.seed"]) for r in children} == {
        ("cvae", "0"),
        ("cvae", "1"),
        ("avae_ts", "0"),
        ("avae_ts", "1"),
    }
    assert {r.data.tags.get("mlflow.parentRunId") for r in children} == {parent}
    tasks = client.search_runs([client.get_experiment_by_name("prg-tasks").experiment_id])
    assert len(tasks) == 4 and {r.data.tags.get("mlflow.parentRunId") for r in tasks} == {parent}
    run = client.get_run(parent)
    assert run.info.status == "FINISHED" and "cvae/coherence_T_given_S/mean" in run.data.metrics
    # evaluation and aggregation again: every evaluation is up to date
    again = subprocess.run(
        [
            str(REPO / ".venv/bin/python"),
            "-m",
            "prg.commands.baselines",
            "evaluate",
            str(out),
            "--families",
            "cvae avae_ts",
            "--seeds",
            "0,1",
            f"paths.data_dir={small_dataset}",
        ],
        cwd=REPO,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert again.returncode == 0, again.stderr[-2000:]
    assert "evaluated in" not in again.stdout
