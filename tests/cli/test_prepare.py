"""All-or-nothing writes (prg.files) and signals held over the steps that must not be cut.

A write is made to fail halfway for real: the kernel's file-size limit (RLIMIT_FSIZE) makes a
write past it fail with EFBIG, the way a full disk fails with ENOSPC. Every writer of the project
must then leave the previous file exactly as it was, no temporary file beside it, and an error
that names the output the user asked for (not a hidden temporary name).
"""

from __future__ import annotations

import json
import resource
import signal
import subprocess
from pathlib import Path

import pytest

from prg.data.synthetic import SyntheticSettings, generate
from prg.data.uji import format_uji
from tests.conftest import BIN, run_cli, small_data_cfg
from tests.helpers.atomic import LIMIT


def test_a_failed_prepare_leaves_the_previous_dataset_and_metrics(tmp_path):
    """The whole command: the dataset is complete (over the limit) but cannot be written; the
    previous dataset and metrics file stay, one line names the file, exit 1."""
    from prg.data.build import build_dataset

    data_dir = tmp_path / "data"
    metrics = tmp_path / "metrics.json"
    build_dataset(small_data_cfg(), data_dir, workers=1, progress=False, figures=False)
    metrics.write_text('{"previous": true}\n')
    folder = data_dir / "prepared" / "synthetic"
    before = {p.name: p.read_bytes() for p in folder.iterdir()}

    def limit():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (LIMIT, resource.RLIM_INFINITY))

    result = subprocess.run(
        [
            str(BIN / "prg-prepare"),
            f"paths.root_dir={tmp_path}",
            f"paths.data_dir={data_dir}",
            "data.synthetic.n_writers=5",
            "data.augment.per_class=3",
            "workers=1",
            "progress=false",
            "figures=false",
            f"metrics_path={metrics}",
        ],
        preexec_fn=limit,
        capture_output=True,
        text=True,
        timeout=300,
    )
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 1, result.stderr[-2000:]
    assert len(lines) == 1 and lines[0].startswith(f"prg-prepare: error: {folder}"), lines
    assert "File too large" in lines[0]
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before
    assert metrics.read_text() == '{"previous": true}\n'
    leftovers = [p for p in tmp_path.rglob(".*") if ".tmp-" in p.name or ".old-" in p.name]
    assert leftovers == []


SMALL = ["data.synthetic.n_writers=6", "data.augment.per_class=2", "workers=1", "progress=false"]


def _uji_file(path: Path, n_writers: int = 6) -> Path:
    """A UJI-format file from another 'writer': synthetic samples, odd cases mixed in."""
    samples = generate(SyntheticSettings(n_writers=n_writers, seed=11))
    text = format_uji(samples)
    extra = (
        "\n// a multi-stroke entry and characters outside the alphabet\n"
        "WORD   ñ   trn_UJI_W99-01  \n NUMSTROKES 1\n POINTS 3 # 0 0 5 5 9 9\n\n"
        "WORD A trn_UJI_W99-01\nNUMSTROKES 2\nPOINTS 2 # 0 0 10 10\nPOINTS 2 # 10 0 0 10\n"
    )
    path.write_bytes((text + extra).replace("\n", "\r\n").encode("utf-8"))
    return path


def test_prepare_synthetic_writes_dataset_figures_and_metrics(tmp_path):
    result = run_cli("prg-prepare", f"paths.root_dir={tmp_path}", *SMALL)
    assert result.returncode == 0, result.stderr
    root = tmp_path / "data" / "prepared" / "synthetic"
    assert {p.name for p in root.iterdir()} == {
        "train.npz",
        "val.npz",
        "test.npz",
        "manifest.json",
        "provenance.json",
        "figures",
    }
    assert len(list((root / "figures").glob("*.png"))) == 3
    metrics = json.loads((tmp_path / "reports/prepare/synthetic/metrics.json").read_text())
    assert metrics["train_writers"] + metrics["val_writers"] + metrics["test_writers"] == 6


def test_prepare_reads_a_uji_file_written_elsewhere(tmp_path):
    uji = _uji_file(tmp_path / "someone_elses_uji.txt")
    result = run_cli(
        "prg-prepare", "data=uji", f"data.uji_path={uji}", f"paths.root_dir={tmp_path}", *SMALL[1:]
    )
    assert result.returncode == 0, result.stderr
    manifest = json.loads((tmp_path / "data/prepared/uji/manifest.json").read_text())
    assert manifest["source"] == "uji"
    assert manifest["selection"]["dropped_not_in_alphabet"] == 1
    assert manifest["selection"]["dropped_multi_stroke"] == 1
    assert manifest["selection"]["kept"] == 6 * 2 * 62


BAD_INPUTS = [
    (["data=mnist"], "mnist"),
    (["data.augment.per_class=-5"], "per_class"),
    (["data.synthetic.n_writers=0"], "n_writers"),
    (["data.splits.train=0.9"], "sum to 1"),
    (["data.no_such_key=1"], "no_such_key"),
    (["data=uji"], "data.uji_path"),
    (["data=uji", "data.uji_path=/no/such/file.txt"], "no such file"),
    (["data=uji", "data.uji_path={only_multi}"], "no usable samples"),
    (["data=uji", "data.uji_path={malformed}"], "line 4"),
    (["workers=0"], "workers"),
]


@pytest.mark.parametrize("args, expected", BAD_INPUTS, ids=[" ".join(a) for a, _ in BAD_INPUTS])
def test_bad_input_gets_one_line_exit_2_and_no_output(tmp_path, args, expected):
    files = {"only_multi": tmp_path / "multi.txt", "malformed": tmp_path / "malformed.txt"}
    files["only_multi"].write_text("WORD a s-01\nNUMSTROKES 2\nPOINTS 1 # 0 0\nPOINTS 1 # 1 1\n")
    files["malformed"].write_text("// header\nWORD a s-01\nNUMSTROKES 1\nPOINTS 3 # 0 0 1 1\n")
    args = [a.format(**files) for a in args]
    root = tmp_path / "root"
    result = run_cli("prg-prepare", f"paths.root_dir={root}", "progress=false", *args)
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2, result.stderr
    assert len(lines) == 1 and lines[0].startswith("prg-prepare: error:"), lines
    assert expected in lines[0]
    assert "Traceback" not in result.stdout + result.stderr
    prepared = root / "data" / "prepared"
    assert not prepared.exists() or not any(prepared.iterdir())


@pytest.mark.parametrize("stage", ["prepare"])
def test_dvc_stage_declares_code_and_conf(stage):
    import yaml

    dvc = yaml.safe_load((Path(__file__).parents[2] / "dvc.yaml").read_text())
    deps = dvc["stages"][stage]["deps"]
    assert "src/prg/data" in deps and "conf/data" in deps
    for dep in deps:
        assert (Path(__file__).parents[2] / dep).exists(), dep
