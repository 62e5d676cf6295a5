"""`prg-write`: text -> word.json/png/svg + DMP rollout + MLflow run; bad input gets one line."""

import csv
import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
from mlflow import MlflowClient

from prg.pipeline.word import WordTrajectory
from prg.recording import read_entities, read_times
from prg.tracking import sqlite_uri
from tests.conftest import run_cli, wait_for_pending_runs
from tests.helpers.write import WORD_OUTPUTS, checkpoint  # noqa: F401 (fixtures)


def test_writes_the_word_its_renderings_rollout_and_an_mlflow_run(tmp_path, checkpoint):
    out = tmp_path / "out"
    result = run_cli(
        "prg-write",
        "text=ab cd",
        f"ckpt={checkpoint}",
        f"out_dir={out}",
        f"paths.root_dir={tmp_path}",
        # the paper's joins, which never lift the pen: an untrained model's scribbles leave the
        # hand joins no clean stroke, and every pair would be a pen lift (tests/prg/pipeline)
        "generate.method=alg1",
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert {p.name for p in out.iterdir()} == WORD_OUTPUTS
    # the process ends without the interpreter's teardown (end_process): its log is all there
    (log_file,) = tmp_path.glob("logs/write/runs/*/cli.log")
    for log_text in (result.stdout, log_file.read_text()):
        assert (
            "wrote 'ab cd' with muse" in log_text and "recorded 'ab cd' as word.rrd" not in log_text
        )
    word = WordTrajectory.from_json(out / "word.json")
    entities = read_entities(out / "word.rrd")
    assert {f"word/letters/{i}_{c}" for i, c in enumerate("abcd")} <= set(entities)
    # one entity per connection stroke: two, the space between the words is a pen lift
    joins = word.segment_kinds.count("connection")
    assert joins == 2 and word.segment_kinds.count("space") == 1
    expected = {f"word/connections/{j}" for j in range(joins)} | {"word/rollout/pen"}
    assert expected <= set(entities) and f"word/connections/{joins}" not in entities
    assert len(read_times(out / "word.rrd", "word/rollout/pen", "time")) == len(
        np.loadtxt(out / "dmp_rollout.csv", delimiter=",", skiprows=1)
    )
    assert word.text == "ab cd" and [c for c, _ in word.letters] == list("abcd")
    assert json.loads((out / "word.json").read_text())["dmp"]["n_basis"] >= 20
    with open(out / "dmp_rollout.csv") as f:
        rows = list(csv.DictReader(f))
    assert float(rows[0]["t_s"]) == 0.0
    assert float(rows[-1]["t_s"]) == pytest.approx(word.duration_s, rel=1e-6)
    # the whole timed motion (its pen-up flags on real letters: tests/test_marks.py)
    motion = np.loadtxt(out / "motion.csv", delimiter=",", skiprows=1)  # t, x, y, pen_down
    assert np.all(np.diff(motion[:, 0]) > 0) and set(motion[:, 3]) <= {0.0, 1.0}
    assert motion[-1, 0] == pytest.approx(word.duration_s, rel=1e-6)
    np.testing.assert_allclose(motion[0, 1:3], word.points[0], atol=1e-5)
    wait_for_pending_runs(tmp_path)  # logged by a background process (mlflow_background=true)
    client = MlflowClient(sqlite_uri(tmp_path / "mlruns.db"))
    (run,) = client.search_runs(
        [client.get_experiment_by_name("prg-tasks").experiment_id], "tags.`prg.task` = 'write'"
    )
    assert run.data.params["text"] == "ab cd"
    assert run.data.metrics["write/points"] == len(word.points)
    artifacts = {a.path for a in client.list_artifacts(run.info.run_id, "word")}
    assert "word/word.json" in artifacts and "word/word.png" in artifacts


def _word_image(data_dir: Path, path: Path, n: int = 3) -> list[int]:
    """Dark-on-light word image of ``n`` test letters, upscaled and set apart; their labels."""
    import numpy as np
    from PIL import Image

    from prg.data.store import load_split

    test = load_split(data_dir / "prepared/synthetic/test.npz")
    canvas = Image.new("L", (n * 140 + 20, 160), 255)
    for i in range(n):
        letter = Image.fromarray(255 - test["image"][i]).resize((112, 112))
        canvas.paste(letter, (20 + 140 * i, 24))
    canvas.save(path)
    return [int(v) for v in np.asarray(test["label"][:n])]


def test_images_channel_alone_or_with_the_text(tmp_path, checkpoint, small_dataset):
    image = tmp_path / "word.png"
    labels = _word_image(small_dataset, image)
    from prg.alphabet import label_to_char

    text = "".join(label_to_char(v) for v in labels)
    for args, expected_text in (
        (["images=" + str(image), f"text={text}"], text),
        (["images=" + str(image)], None),
    ):
        out = tmp_path / f"out{len(args)}"
        result = run_cli(
            "prg-write",
            *args,
            f"ckpt={checkpoint}",
            f"out_dir={out}",
            f"paths.root_dir={tmp_path}",
            "mlflow=false",
        )
        assert result.returncode == 0, result.stderr[-2000:]
        word = WordTrajectory.from_json(out / "word.json")
        assert len(word.letters) == 3  # the three letters were segmented and written
        if expected_text:
            assert word.text == expected_text


def test_trajectories_channel(tmp_path, checkpoint, small_dataset):
    from prg.data.store import load_split

    test = load_split(small_dataset / "prepared/synthetic/test.npz")
    strokes = [(test["traj"][i].reshape(-1, 2) * 37 + 5).tolist() for i in range(2)]
    path = tmp_path / "letters.json"
    path.write_text(json.dumps({"strokes": strokes, "y_down": False}))
    out = tmp_path / "out"
    result = run_cli(
        "prg-write",
        f"trajectories={path}",
        "text=ab",
        f"ckpt={checkpoint}",
        f"out_dir={out}",
        f"paths.root_dir={tmp_path}",
        "mlflow=false",
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert WordTrajectory.from_json(out / "word.json").text == "ab"


def test_audio_channel_speech_to_word_with_recording(tmp_path, checkpoint):
    wav = tmp_path / "jump.wav"
    subprocess.run(["espeak-ng", "-v", "en+f3", "-s", "130", "-w", str(wav), "jump"], check=True)
    out = tmp_path / "out"
    result = run_cli(
        "prg-write",
        f"audio={wav}",
        "speech.lexicon=[bell,cat,jump]",
        f"ckpt={checkpoint}",
        f"out_dir={out}",
        f"paths.root_dir={tmp_path}",
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert WordTrajectory.from_json(out / "word.json").text == "jump"
    entities = read_entities(out / "word.rrd")
    assert {"inputs/audio", "inputs/waveform", "inputs/transcript"} <= set(entities)
    wait_for_pending_runs(tmp_path)  # logged by a background process (mlflow_background=true)
    client = MlflowClient(sqlite_uri(tmp_path / "mlruns.db"))
    (run,) = client.search_runs([client.get_experiment_by_name("prg-tasks").experiment_id])
    assert run.data.params["speech.word"] == "jump" and run.data.params["audio"] == str(wav)
    assert run.data.metrics["write/recognise_ms"] > 0


@pytest.mark.parametrize(
    "args, expected",
    [
        (["text=h@llo"], "unsupported characters '@'"),  # from the task
        (  # from Hydra's override grammar, the override named
            ["text=héllo, wörld!"],
            "cannot read text=héllo, wörld!: token recognition error at: 'é'; a value with",
        ),
    ],
)
def test_the_command_prints_one_line_and_exits_2(tmp_path, checkpoint, args, expected):
    out = tmp_path / "out"
    result = run_cli("prg-write", *args, f"ckpt={checkpoint}", f"out_dir={out}")
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2, result.stderr[-2000:]
    assert len(lines) == 1 and lines[0].startswith("prg-write: error:"), lines
    assert expected in lines[0]
    assert not out.exists()
