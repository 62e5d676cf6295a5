"""Tests of ``prg.commands.write`` (moved from the suite on: `prg-write`: text -> word.json/png/svg
+ DMP rollout + MLflow run; bad input gets one line)."""

import subprocess
import wave

import numpy as np
import pytest

from prg.commands.cli import compose_config
from prg.commands.write import write
from prg.errors import UncertainWordError, UsageError
from prg.pipeline.word import WordTrajectory
from tests.helpers.write import WORD_FOLDER, WORD_OUTPUTS, checkpoint  # noqa: F401 (fixtures)

BAD = [
    (["text= "], "text is empty"),
    (["mlflow=false"], "nothing to write"),
    (["images={tmp}/none.png"], "none.png"),
    (["text=abcd", "images={tmp}"], "holds no"),
    (["trajectories={tmp}/none.json"], "does not exist"),
    (["text=h@llo"], "unsupported characters '@'"),
    (["text='@!'", "on_unknown=skip"], "no letters to write"),
    (["text=hi", "on_unknown=ignore"], "error or skip"),
    (["text=hi", "ckpt={tmp}/none.ckpt"], "does not exist"),
    (["text=hi", "generate.method=zigzag"], "connection method zigzag; accepted: hand, alg1,"),
    (["text=hi", "generate.speed_cm_s=-1"], "speed"),
    (["text=hi", "audio={tmp}/silence.wav"], "give one of them"),
    (["audio={tmp}/none.wav"], "none.wav"),
    (["audio={tmp}/silence.wav"], "silent"),
    (["audio={tmp}/silence.wav", "speech.backend=kaldi"], "speech backend 'kaldi' is unknown"),
    (["audio={tmp}/silence.wav", "speech.lexicon={tmp}/none.txt"], "not a readable word list"),
    (["audio={tmp}/silence.wav", "speech.min_lead=-1"], "speech.min_lead"),
]


@pytest.mark.parametrize("args, expected", BAD, ids=[" ".join(a) for a, _ in BAD])
def test_bad_input_is_refused_in_one_line_and_writes_nothing(tmp_path, checkpoint, args, expected):
    out = tmp_path / "out"
    silence = np.zeros(16000, dtype=np.int16)
    with wave.open(str(tmp_path / "silence.wav"), "wb") as f:
        f.setnchannels(1), f.setsampwidth(2), f.setframerate(16000)
        f.writeframes(silence.tobytes())
    args = [a.format(tmp=tmp_path) for a in args]
    if not any(a.startswith("ckpt=") for a in args):
        args.append(f"ckpt={checkpoint}")
    cfg = compose_config("write", [*args, f"out_dir={out}", f"paths.root_dir={tmp_path}"])
    with pytest.raises(UsageError) as refused:
        write(cfg)
    assert expected in str(refused.value) and "\n" not in str(refused.value)
    assert not out.exists()


def test_a_word_not_heard_clearly_enough_is_refused_in_one_line(tmp_path, checkpoint):
    """speech.min_lead: when no lexicon word leads the others by it, nothing is written and
    the one-line error asks the speaker to repeat (exit 2 from the command line)."""
    wav = tmp_path / "jump.wav"
    subprocess.run(["espeak-ng", "-v", "en+f3", "-s", "130", "-w", str(wav), "jump"], check=True)
    out = tmp_path / "out"
    speech = ["speech.lexicon=[bell,cat,jump]", "speech.rescore=true"]
    common = [f"audio={wav}", *speech, f"ckpt={checkpoint}", "mlflow=false", "record=false"]
    cfg = compose_config("write", [*common, "speech.min_lead=1000", f"out_dir={out}"])
    with pytest.raises(UncertainWordError) as refused:
        write(cfg)
    message = str(refused.value)
    assert "not sure whether 'jump' or" in message and "say it again" in message
    assert "\n" not in message and not out.exists()
    word, _ = write(compose_config("write", [*common, "speech.min_lead=1", f"out_dir={out}"]))
    assert word.text == "jump"


def test_unknown_characters_are_skipped_on_request(tmp_path, checkpoint):
    out = tmp_path / "out"
    cfg = compose_config(
        "write",
        [
            'text="héllo, wörld!"',
            "on_unknown=skip",
            f"ckpt={checkpoint}",
            f"out_dir={out}",
            "mlflow=false",
            "record=false",
        ],
    )
    word, _ = write(cfg)
    assert word.text == "hllo wrld"
    assert WordTrajectory.from_json(out / "word.json").text == "hllo wrld"


def test_each_word_gets_its_own_folder_named_by_text_and_time(tmp_path, checkpoint):
    """The default out_dir: outputs/write/<family>/<text>-<time>, a new folder every time."""
    import re

    args = ["text=ab cd", f"ckpt={checkpoint}", f"paths.root_dir={tmp_path}", "mlflow=false"]
    folders = [write(compose_config("write", args))[1] for _ in range(2)]
    assert folders[0] != folders[1]
    family = tmp_path / "outputs" / "write" / "muse"
    assert sorted(family.iterdir()) == sorted(folders)
    for folder in folders:
        assert re.fullmatch(WORD_FOLDER, folder.name), folder.name
        assert {p.name for p in folder.iterdir()} == WORD_OUTPUTS
        assert WordTrajectory.from_json(folder / "word.json").text == "ab cd"


@pytest.mark.parametrize(
    "out_dir, expected",
    [("'{tmp}/{{word}}'", "unknown placeholder {word}"), ("'{tmp}/{{text'", "placeholders")],
    ids=["unknown-field", "unpaired-brace"],
)
def test_a_bad_folder_template_is_refused_before_writing(tmp_path, checkpoint, out_dir, expected):
    cfg = compose_config(
        "write",
        ["text=hi", f"ckpt={checkpoint}", f"out_dir={out_dir.format(tmp=tmp_path)}"],
    )
    with pytest.raises(UsageError) as refused:
        write(cfg)
    assert expected in str(refused.value) and "out_dir" in str(refused.value)
    assert list(tmp_path.iterdir()) == []
