"""`prg-dictaphone`: the paper's Table II from espeak-ng speech and test-split letter images."""

import json

import numpy as np
import pytest
from PIL import Image

from prg.commands.cli import compose_config
from prg.commands.dictaphone import dictaphone
from prg.errors import UsageError
from prg.pipeline.speech import load_audio
from prg.pipeline.word import WordTrajectory
from prg.recording import read_entities
from tests.conftest import run_cli


@pytest.fixture(scope="module")
def table(tmp_path_factory, untrained_muse_checkpoint, small_dataset):
    root = tmp_path_factory.mktemp("dictaphone")
    out = root / "reports"
    result = run_cli(
        "prg-dictaphone",
        "words=[cat,jump]",
        "speech.lexicon=[bell,cat,jump]",
        f"ckpt={untrained_muse_checkpoint}",
        f"paths.data_dir={small_dataset}",
        f"paths.root_dir={root}",
        f"out_dir={out}",
        "mlflow=false",
    )
    assert result.returncode == 0, result.stderr[-3000:]
    return out


def test_every_word_is_written_from_sound_and_from_images(table):
    metrics = json.loads((table / "metrics.json").read_text())
    cases = {(r["word"], r["channel"]) for r in metrics["rows"]}
    assert cases == {(w, c) for w in ("cat", "jump") for c in ("sound", "image")}
    for row in metrics["rows"]:
        word = WordTrajectory.from_json(table / row["word"] / row["channel"] / "word.json")
        assert word.text == row["written"]
        assert 0 <= row["dmp_rmse_mm"] < 1.0
    # the lexicon makes espeak-ng's default voice reliable for these words (measured)
    sound = [r for r in metrics["rows"] if r["channel"] == "sound"]
    assert [r["perceived"] for r in sound] == ["cat", "jump"]
    assert metrics["sound_accuracy"] == 1.0


def test_the_inputs_are_kept_and_reusable(table):
    audio = load_audio(table / "inputs" / "cat.wav")
    assert 0.2 < len(audio) / 16000 < 3.0
    letters = sorted((table / "inputs" / "jump").glob("*.png"))
    assert [p.stem for p in letters] == ["0_j", "1_u", "2_m", "3_p"]
    image = np.asarray(Image.open(letters[0]))
    assert image.shape == (28, 28) and image.mean() > 128  # dark ink on light paper


def test_recordings_hold_the_inputs_of_their_channel(table):
    sound = read_entities(table / "cat" / "sound" / "word.rrd")
    assert {"inputs/audio", "inputs/transcript", "word/rollout/pen"} <= set(sound)
    image = read_entities(table / "jump" / "image" / "word.rrd")
    assert {f"inputs/images/{i}_{c}" for i, c in enumerate("jump")} <= set(image)
    assert "inputs/audio" not in image


def test_table_and_figure(table):
    rows = [line for line in (table / "table2.md").read_text().splitlines() if line[:2] == "| "]
    assert [r.split(" | ")[:2] for r in rows[1:]] == [
        ["| cat", "sound"],
        ["| cat", "image"],
        ["| jump", "sound"],
        ["| jump", "image"],
    ]
    figure = Image.open(table / "table2.png")
    assert figure.size[0] > 2 * figure.size[1]  # one column per word and channel


@pytest.mark.parametrize(
    "args, expected",
    [
        (["words=[cat]", "channels=[smell]"], "choose from sound, image"),
        (["words=['c@t']"], "unsupported characters '@'"),
        (["words=[cat]", "channels=[sound]", "voice=klingon-xx"], "espeak-ng could not speak"),
    ],
)
def test_bad_input_is_refused_in_one_line_and_writes_nothing(
    tmp_path, untrained_muse_checkpoint, args, expected
):
    out = tmp_path / "out"
    cfg = compose_config(
        "dictaphone",
        [*args, f"ckpt={untrained_muse_checkpoint}", f"out_dir={out}", "mlflow=false"],
    )
    with pytest.raises(UsageError) as refused:
        dictaphone(cfg)
    assert expected in str(refused.value) and "\n" not in str(refused.value)
    assert not out.exists()


def test_image_reading_is_scored_exact_and_up_to_shape_twins(table):
    from prg.evaluation.dictaphone import same_shapes

    assert same_shapes("beii", "bell") and same_shapes("cat", "cat")
    assert same_shapes("C0t", "cot") and not same_shapes("cat", "cot")
    assert not same_shapes("bel", "bell") and not same_shapes("be!l", "bell")
    metrics = json.loads((table / "metrics.json").read_text())
    images = [r for r in metrics["rows"] if r["channel"] == "image"]
    for row in images:
        assert row["correct_folded"] == same_shapes(row["perceived"], row["word"])
        assert row["correct_folded"] or not row["correct"]
    folded = np.mean([r["correct_folded"] for r in images])
    assert metrics["image_read_accuracy_folded"] == pytest.approx(folded, abs=1e-3)
