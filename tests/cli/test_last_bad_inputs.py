"""The last bad inputs of each command (issue 46): one line naming the input and what is
accepted, the right exit code, nothing written. Real commands, real files."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
import torch

from tests.conftest import run_cli
from tests.helpers.train import FAST


def one_line(result, code: int, command: str) -> str:
    lines = result.stderr.strip().splitlines()
    assert result.returncode == code, result.stderr[-3000:]
    assert len(lines) == 1, lines
    assert lines[0].startswith(f"{command}: error: "), lines
    return lines[0]


def files_below(folder: Path) -> list[Path]:
    """Every file under ``folder`` but Hydra's run logs (``logs/``)."""
    logs = folder / "logs"
    return sorted(p for p in folder.rglob("*") if p.is_file() and logs not in p.parents)


CHECKPOINT_LIKE = [
    ({"state_dict": {}, "hyper_parameters": {}}, "its hyper_parameters have no model._target_"),
    ({"state_dict": {}, "hyper_parameters": {"model": 3}}, "no model._target_"),
    ({"state_dict": {}, "hyper_parameters": None}, "no hyper_parameters"),
    ({"state_dict": [1], "hyper_parameters": {}}, "no state_dict of named tensors"),
]


def test_train_resume_from_a_checkpoint_like_dict(tmp_path, small_dataset):
    """The real command on one checkpoint-like dict; the reader it calls on every kind below."""
    content, problem = CHECKPOINT_LIKE[0]
    ckpt = tmp_path / "like.ckpt"
    torch.save(content, ckpt)
    result = run_cli(
        "prg-train",
        f"paths.root_dir={tmp_path}",
        f"paths.data_dir={small_dataset}",
        *FAST,
        f"ckpt_path={ckpt}",
    )
    line = one_line(result, 2, "prg-train")
    assert f"checkpoint {ckpt} is not a prg training checkpoint (" in line
    assert f"{problem}); accepted" in line
    assert "accepted: a model.ckpt, best.ckpt or last.ckpt written by prg-train" in line
    assert not (tmp_path / "checkpoints").exists()


@pytest.mark.parametrize(
    "content, problem",
    CHECKPOINT_LIKE,
    ids=["no-model", "model-not-a-dict", "hparams-none", "weights-not-a-dict"],
)
def test_every_checkpoint_like_dict_is_named_by_what_it_lacks(tmp_path, content, problem):
    from prg.errors import UsageError
    from prg.models.checkpoint import read_checkpoint

    ckpt = tmp_path / "like.ckpt"
    torch.save(content, ckpt)
    with pytest.raises(UsageError) as refused:
        read_checkpoint(ckpt)
    line = str(refused.value)
    assert "\n" not in line and f"checkpoint {ckpt} is not a prg training checkpoint (" in line
    assert (
        f"{problem}); accepted: a model.ckpt, best.ckpt or last.ckpt written by prg-train" in line
    )


def test_unknown_speech_language(tmp_path, untrained_muse_checkpoint):
    ckpt = f"ckpt={untrained_muse_checkpoint}"
    result = run_cli("prg-write", "text=hi", ckpt, "speech.language=klingon", cwd=tmp_path)
    line = one_line(result, 2, "prg-write")
    assert "speech.language 'klingon' is unknown: accepted are whisper's language codes" in line
    assert " en, " in line
    assert files_below(tmp_path) == []


def test_a_text_file_named_mp3_gets_no_decoder_lines(tmp_path, untrained_muse_checkpoint):
    fake = tmp_path / "word.mp3"
    fake.write_text("this is not sound\n" * 20)
    ckpt = f"ckpt={untrained_muse_checkpoint}"
    result = run_cli("prg-write", f"audio={fake}", ckpt, "mlflow=false", cwd=tmp_path)
    line = one_line(result, 2, "prg-write")  # no "Note: Illegal Audio-MPEG-Header" beside it
    assert f"{fake}: not an audio file that can be read (accepted: WAV, FLAC" in line
    assert files_below(tmp_path) == [fake]


@pytest.mark.parametrize(
    "args, expected",
    [
        (["--cfg", "job", "seed=["], "cannot read seed=[: no viable alternative at input '['"),
        (["-m", "seed=0,1", "model=["], "cannot read model=[: no viable alternative at input"),
        (["--multirun", "model=cvae,musee"], "unknown model musee; accepted: "),
        (["--cfg", "job", "nosuchkey=1"], "unknown key nosuchkey; accepted top-level keys"),
        (["--cfg", "job", "data=nope"], "unknown data nope; accepted: synthetic, uji"),
        (["-m", "seed=0,1", "trainer.max_epochs=0,-3"], "trainer.max_epochs must be"),
        (["-m", "seed=0,1", "--cfg", "job"], "--multirun and --cfg cannot be combined"),
    ],
    ids=[
        "cfg-syntax",
        "multirun-syntax",
        "multirun-option",
        "cfg-key",
        "cfg-group",
        "sweep-range",
        "two-modes",
    ],
)
def test_malformed_overrides_with_hydra_flags(tmp_path, args, expected):
    result = run_cli("prg-train", *args, cwd=tmp_path)
    assert expected in one_line(result, 2, "prg-train")
    assert result.stdout == ""  # no usage text, no config printed
    assert files_below(tmp_path) == []


def test_cfg_with_good_overrides_still_prints_the_config(tmp_path):
    result = run_cli("prg-train", "--cfg", "job", "seed=3", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "seed: 3" in result.stdout


@pytest.mark.parametrize(
    "words, expected",
    [
        ("words=bell", "words must be a list of single words, e.g. words=[bell,cat], got 'bell'"),
        ("words=7", "words must be a list of single words"),
    ],
)
def test_dictaphone_words_not_a_list(tmp_path, words, expected):
    result = run_cli("prg-dictaphone", words, "mlflow=false", cwd=tmp_path)
    assert expected in one_line(result, 2, "prg-dictaphone")
    assert files_below(tmp_path) == []


@pytest.mark.parametrize("command", ["prg-write", "prg-dictaphone"])
def test_out_dir_that_is_a_symlink_loop(tmp_path, command, untrained_muse_checkpoint):
    loop = tmp_path / "loop"
    loop.symlink_to(loop)
    args = ["text=hi"] if command == "prg-write" else ["words=[hi]"]
    result = run_cli(
        command, *args, f"ckpt={untrained_muse_checkpoint}", f"out_dir={loop}/sub", cwd=tmp_path
    )
    line = one_line(result, 2, command)
    assert f"out_dir {loop}/sub: {loop} is a symbolic link that loops" in line
    assert files_below(tmp_path) == []


def test_data_name_with_a_newline(tmp_path):
    result = run_cli("prg-prepare", "data.name='a\nb'", "workers=1", cwd=tmp_path)
    line = one_line(result, 2, "prg-prepare")
    assert "data.name='a\\nb' holds a control character" in line
    assert "accepted are printable characters without '/'" in line
    assert files_below(tmp_path) == []


def test_a_read_only_mlflow_store(tmp_path, untrained_muse_checkpoint):
    """A store that refuses writes (SQLite opened read-only, as on a read-only disk): one line
    naming the store and what to do; the word is not left half-logged or written."""
    store = tmp_path / "store.db"
    ok = run_cli(
        "prg-write",
        "text=hi",
        f"ckpt={untrained_muse_checkpoint}",
        f"out_dir={tmp_path / 'first'}",
        "mlflow_background=false",
        cwd=tmp_path,
        env={"MLFLOW_TRACKING_URI": f"sqlite:///{store}"},
    )
    assert ok.returncode == 0, ok.stderr[-3000:]
    uri = f"sqlite:///file:{store}?mode=ro&uri=true"
    out = tmp_path / "second"
    result = run_cli(
        "prg-write",
        "text=hi",
        f"ckpt={untrained_muse_checkpoint}",
        f"out_dir={out}",
        "mlflow_background=false",
        cwd=tmp_path,
        env={"MLFLOW_TRACKING_URI": uri},
    )
    line = one_line(result, 1, "prg-write")
    assert line == (
        f"prg-write: error: MLflow store {uri} is read-only: make it writable, or log elsewhere "
        "with logger.tracking_uri=URI or MLFLOW_TRACKING_URI (mlflow=false: no run)"
    )
    assert not out.exists()


def test_dictaphone_words_never_share_a_folder(tmp_path, untrained_muse_checkpoint, small_dataset):
    """Duplicates, a word named like the table's inputs folder, the same word in two cases: each
    distinct word gets its own folder; the metrics name the checkpoint from the project root."""
    models = tmp_path / "models" / "muse"
    models.mkdir(parents=True)
    shutil.copyfile(untrained_muse_checkpoint, models / "model.ckpt")
    out = tmp_path / "reports" / "dictaphone"
    result = run_cli(
        "prg-dictaphone",
        "words=[inputs,cat,cat,Cat]",
        "channels=[image]",
        f"paths.data_dir={small_dataset}",
        f"out_dir={out}",
        "mlflow=false",
        "record=false",
        cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    metrics = json.loads((out / "metrics.json").read_text())
    rows = [(r["word"], r["folder"]) for r in metrics["rows"]]
    assert rows == [("inputs", "inputs-2"), ("cat", "cat"), ("Cat", "Cat-2")]
    assert metrics["ckpt"] == "models/muse/model.ckpt"
    for word, folder in rows:
        assert json.loads((out / folder / "image" / "word.json").read_text())["text"]
        assert len(list((out / "inputs" / folder).glob("*.png"))) == len(word)
    assert sorted(p.name for p in out.iterdir() if p.is_dir()) == sorted(
        ["inputs", "inputs-2", "cat", "Cat-2"]
    )
