"""`prg-train`: MLflow records, checkpoints, resume, sweeps, bad input — real SQLite stores."""

import pytest

from prg.commands.train import train
from tests.conftest import run_cli
from tests.helpers.train import FAST, _cfg, _client

SWEEPS = {
    "basic": ["model=cvae,avae_ts"],
    # 2 workers writing to one SQLite store at once
    "joblib": [
        "model=cvae,avae_ts",
        "seed=0,1",
        "hydra/launcher=joblib",
        "hydra.launcher.n_jobs=2",
    ],
}


@pytest.mark.parametrize(
    "launcher",
    [
        "basic",
        # slow (44 s): the concurrent writes to one store are also tests/test_scale_out.py's
        pytest.param("joblib", marks=pytest.mark.slow),
    ],
)
def test_multirun_jobs_land_under_one_parent_run(tmp_path, small_dataset, launcher):
    result = run_cli(
        "prg-train",
        "-m",
        *SWEEPS[launcher],
        f"paths.root_dir={tmp_path}",
        f"paths.data_dir={small_dataset}",
        "trainer.max_epochs=1",
        "trainer.limit_train_batches=3",
        "trainer.limit_val_batches=2",
        "trainer.enable_progress_bar=false",
        "~callbacks.figures",
        timeout=900,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    logs = [p.read_text() for p in (tmp_path / "logs").rglob("*.log")]
    assert not any("database is locked" in t for t in [result.stdout, result.stderr, *logs])
    client = _client(tmp_path)
    runs = client.search_runs([client.get_experiment_by_name("prg").experiment_id])
    (parent,) = [r for r in runs if r.data.tags.get("prg.sweep") == "parent"]
    children = [r for r in runs if r is not parent]
    jobs = {(c.data.tags["prg.family"], c.data.tags["prg.seed"]) for c in children}
    expected = {("cvae", "0"), ("avae_ts", "0")}
    if launcher == "joblib":
        expected |= {("cvae", "1"), ("avae_ts", "1")}
    assert len(children) == len(expected) and jobs == expected
    assert {c.data.tags.get("mlflow.parentRunId") for c in children} == {parent.info.run_id}
    assert parent.info.status == "FINISHED"
    for child in children:
        assert child.info.status == "FINISHED"
        assert {"train/loss", "val/loss"} <= set(child.data.metrics)
        family, seed = child.data.tags["prg.family"], child.data.tags["prg.seed"]
        # the description's command reruns this job alone
        assert f"prg-train model={family}" in child.data.tags["mlflow.note.content"]
        assert (f" seed={seed}" in child.data.tags["mlflow.note.content"]) == (launcher != "basic")
        assert [a.path for a in client.list_artifacts(child.info.run_id, "checkpoints")] == [
            "checkpoints/best.ckpt"
        ]


BAD = [
    (["model=transformer"], "transformer"),
    (["ckpt_path=/no/such.ckpt"], "does not exist"),
    (["ckpt_path={text}"], "not a readable checkpoint"),
    (["model=avae_ti", "data.loader.modalities=[traj,label]"], "image"),
    (["trainer.max_epochs=banana"], "max_epochs"),
]


@pytest.mark.parametrize("args, expected", BAD, ids=[" ".join(a) for a, _ in BAD])
def test_bad_input_gets_one_line_and_exit_2(tmp_path, small_dataset, args, expected):
    text = tmp_path / "notes.ckpt"
    text.write_text("not a checkpoint")
    args = [a.format(text=text) for a in args]
    result = run_cli(
        "prg-train", f"paths.root_dir={tmp_path}", f"paths.data_dir={small_dataset}", *FAST, *args
    )
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2, result.stderr[-2000:]
    assert len(lines) == 1 and lines[0].startswith("prg-train: error:"), lines
    assert expected in lines[0]
    assert "Traceback" not in result.stderr


def test_checkpoint_of_another_family_is_refused(tmp_path, small_dataset):
    train(_cfg(tmp_path, small_dataset, "model=cvae", "trainer.max_epochs=1"))
    ckpt = tmp_path / "checkpoints/prg/cvae-seed0/last.ckpt"
    result = run_cli(
        "prg-train",
        "model=avae_ts",
        f"ckpt_path={ckpt}",
        f"paths.root_dir={tmp_path}",
        f"paths.data_dir={small_dataset}",
        *FAST,
    )
    assert result.returncode == 2
    assert "holds a prg.models.cvae.CVAE model" in result.stderr


def test_bf16_on_a_cpu_without_bf16_kernels_trains_in_fp32(tmp_path, small_dataset):
    held_to_avx2 = {"ONEDNN_MAX_CPU_ISA": "AVX2", "MKL_ENABLE_INSTRUCTIONS": "AVX2"}
    result = run_cli(
        "prg-train",
        "model=cvae",
        "trainer.precision=bf16-mixed",
        f"paths.root_dir={tmp_path}",
        f"paths.data_dir={small_dataset}",
        *FAST,
        env=held_to_avx2,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert "trainer.precision=bf16-mixed: this CPU has no bf16 kernels" in result.stdout
    run = _client(tmp_path).search_runs(
        [_client(tmp_path).get_experiment_by_name("prg").experiment_id]
    )[0]
    assert run.data.params["trainer.precision"] == "32-true"
