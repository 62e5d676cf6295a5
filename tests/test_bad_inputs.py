"""Bad input to every command: one line naming the problem, exit code 2 (usage) or 1 (run
time), no traceback, and nothing written.

One table, ``CASES``, covers the seven commands. ``{name}`` placeholders in a case's arguments
are files made once by :func:`bad_files` (a corrupt WAV, a text file named ``.ckpt``, a
truncated checkpoint ...); ``{tmp}`` is the test's own folder, which is also the working
directory and ``paths.root_dir``, so even a default output path lands where the before/after
snapshot of both folders looks. No file may appear, change or vanish there, except in Hydra's
own log folder (``paths.log_dir``). Each case runs the command's console-script ``main`` in this
process (the function the installed script calls; a subprocess spends seconds importing torch);
``test_console_scripts_behave_the_same`` runs one case of each kind of entry point (Hydra,
argparse) through the installed scripts.

"Unwritable" output: the tests run as root, whom file modes do not stop, so the output paths
are ones no user can create: below a regular file, and below ``/sys`` (sysfs refuses new
folders, root included).
"""

from __future__ import annotations

import importlib.metadata
import logging
import os
import struct
import sys
import wave
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import REPO, run_cli

HYDRA_COMMANDS = (
    "prg-prepare",
    "prg-train",
    "prg-evaluate",
    "prg-write",
    "prg-dictaphone",
    "prg-simulate",
)


@dataclass(frozen=True)
class Case:
    id: str
    command: str
    args: tuple[str, ...]
    code: int  # 2: usage error, 1: run-time failure
    expected: str  # the one line must contain this


def case(id: str, command: str, args: str | list[str], code: int, expected: str) -> Case:
    return Case(id, command, tuple(args.split() if isinstance(args, str) else args), code, expected)


CASES = [
    # ---- prg-prepare
    case("prepare-negative-count", "prg-prepare", "data.augment.per_class=-5", 2, "per_class"),
    case("prepare-non-numeric", "prg-prepare", "data.synthetic.n_writers=many", 2, "n_writers"),
    case(
        "prepare-uji-garbage", "prg-prepare", "data=uji data.uji_path={garbage}", 2, "garbage.txt"
    ),
    case("prepare-uji-folder", "prg-prepare", "data=uji data.uji_path={folder}", 2, "a-folder"),
    case(
        "prepare-out-below-file",
        "prg-prepare",
        "data.synthetic.n_writers=5 paths.data_dir={file}/data",
        2,
        "a-file.txt",
    ),
    case(
        "prepare-metrics-in-sys",
        "prg-prepare",
        "data.synthetic.n_writers=5 metrics_path=/sys/prg/m.json",
        2,
        "/sys/prg",
    ),
    case(
        "prepare-download-bad-archive",
        "prg-prepare",
        "data=uji data.download=true data.uji_url=file://{garbage}",
        1,
        "checksum",
    ),
    case(
        "prepare-download-refused",
        "prg-prepare",
        "data=uji data.download=true data.uji_url=http://127.0.0.1:9/uji.zip",
        1,
        "127.0.0.1:9",
    ),
    case("prepare-log-dir-below-file", "prg-prepare", "paths.log_dir={file}/logs", 2, "a-file.txt"),
    # ---- prg-train
    case("train-non-numeric", "prg-train", "trainer.max_epochs=banana", 2, "max_epochs"),
    case("train-negative-seed", "prg-train", "seed=-1", 2, "seed"),
    case("train-no-dataset", "prg-train", "paths.data_dir={tmp}/nodata", 2, "prg-prepare"),
    case("train-text-ckpt", "prg-train", "ckpt_path={text_ckpt}", 2, "notes.ckpt"),
    case("train-truncated-ckpt", "prg-train", "ckpt_path={truncated_ckpt}", 2, "truncated.ckpt"),
    case("train-ckpt-is-a-folder", "prg-train", "ckpt_path={folder}", 2, "is a folder"),
    case("train-export-below-file", "prg-train", "export_dir={file}/m", 2, "export_dir"),
    case("train-ckpt-dir-in-sys", "prg-train", "checkpoint_dir=/sys/prg/ckpt", 2, "/sys/prg"),
    # ---- prg-evaluate
    case("evaluate-missing-models", "prg-evaluate", "families=[muse]", 2, "does not exist"),
    case(
        "evaluate-truncated-ckpt", "prg-evaluate", "+checkpoints.m={truncated_ckpt}", 2, "truncated"
    ),
    case("evaluate-zero-k", "prg-evaluate", "likelihood.k_marginal=0", 2, "k_marginal"),
    case(
        "evaluate-non-numeric-temperature",
        "prg-evaluate",
        "coherence.temperatures.mean=hot",
        2,
        "temperatures.mean",
    ),
    case("evaluate-no-test-split", "prg-evaluate", "+checkpoints.m={ckpt}", 2, "test.npz"),
    case(
        "evaluate-report-below-file",
        "prg-evaluate",
        "+checkpoints.m={ckpt} report_dir={file}/reports",
        2,
        "a-file.txt",
    ),
    # ---- prg-write
    case("write-unknown-characters", "prg-write", "text=h@llo", 2, "'@'"),
    case("write-empty-text", "prg-write", "text=", 2, "text is empty"),
    case("write-corrupt-audio", "prg-write", "audio={corrupt_wav}", 2, "corrupt.wav"),
    case("write-silent-audio", "prg-write", "audio={silent_wav}", 2, "silent"),
    case("write-empty-audio", "prg-write", "audio={empty_wav}", 2, "empty"),
    case("write-audio-is-a-folder", "prg-write", "audio={folder}", 2, "a-folder"),
    case("write-text-as-image", "prg-write", "images={text_png}", 2, "letters.png"),
    case("write-blank-image", "prg-write", "images={blank_png}", 2, "blank"),
    case("write-huge-image", "prg-write", "images={huge_png}", 2, "huge.png"),
    case("write-noise-photo", "prg-write", "text=cat images={noise_jpg}", 2, "3 letters"),
    case("write-truncated-ckpt", "prg-write", "text=hi ckpt={truncated_ckpt}", 2, "truncated"),
    case("write-zero-speed", "prg-write", "text=hi generate.speed_cm_s=0", 2, "speed"),
    case("write-out-below-file", "prg-write", "text=hi out_dir={file}/out", 2, "a-file.txt"),
    case("write-out-in-sys", "prg-write", "text=hi out_dir=/sys/prg-out", 2, "/sys/prg-out"),
    case("write-out-is-a-file", "prg-write", "text=hi out_dir={file}", 2, "a-file.txt"),
    # ---- prg-dictaphone
    case("dictaphone-unknown-characters", "prg-dictaphone", "words=[b@ll]", 2, "'@'"),
    case("dictaphone-no-words", "prg-dictaphone", "words=[]", 2, "words"),
    case("dictaphone-unknown-channel", "prg-dictaphone", "channels=[smell]", 2, "smell"),
    case("dictaphone-negative-speed", "prg-dictaphone", "speed=-5", 2, "speed"),
    case("dictaphone-text-ckpt", "prg-dictaphone", "ckpt={text_ckpt}", 2, "notes.ckpt"),
    case("dictaphone-no-test-split", "prg-dictaphone", "channels=[image]", 2, "test.npz"),
    case("dictaphone-out-below-file", "prg-dictaphone", "out_dir={file}/dict", 2, "a-file.txt"),
    # ---- prg-simulate
    case("simulate-unknown-robot", "prg-simulate", "word={word} robot=kuka", 2, "kuka"),
    case(
        "simulate-word-too-large",
        "prg-simulate",
        "word={word} scale=40 workspace_step_cm=4",
        2,
        "cm wide",
    ),
    case(
        "simulate-text-too-long",
        "prg-simulate",
        [
            "text='the quick brown fox jumps over the lazy dog'",
            "layout.letter_height=3",
            "workspace_step_cm=4",
            "generate.method=straight",
            "generate.speed_cm_s=100",
        ],
        2,
        "cm wide",
    ),
    case("simulate-corrupt-word", "prg-simulate", "word={bad_json}", 2, "not valid JSON"),
    case("simulate-word-is-a-folder", "prg-simulate", "word={folder}", 2, "a-folder"),
    case("simulate-zero-tempo", "prg-simulate", "word={word} tempo=0", 2, "tempo"),
    case("simulate-non-numeric-scale", "prg-simulate", "word={word} scale=big", 2, "scale"),
    case("simulate-out-below-file", "prg-simulate", "word={word} out_dir={file}/sim", 2, "a-file"),
    # ---- prg-study
    case("study-no-command", "prg-study", [], 2, "choose a command"),
    case("study-missing-file", "prg-study", "build {tmp}/nope.yaml", 2, "no such study file"),
    case("study-bad-yaml", "prg-study", "build {bad_yaml}", 2, "not valid YAML"),
    case("study-bad-value", "prg-study", "build {turing} --set participants=-3", 2, "participants"),
    case(
        "study-build-out-below-file", "prg-study", "build {turing} --out {file}/b", 2, "a-file.txt"
    ),
    case("study-responses-missing", "prg-study", "analyze {tmp}/none.csv", 2, "none.csv"),
    case("study-responses-corrupt", "prg-study", "analyze {bad_csv}", 2, "responses.csv"),
    case("study-alpha-out-of-range", "prg-study", "analyze {bad_csv} --alpha 7", 2, "alpha"),
    case("study-power-out-below-file", "prg-study", "power turing --out {file}/p.csv", 2, "a-file"),
    case("study-power-out-device", "prg-study", "power turing --out /dev/full", 2, "/dev/full"),
    case(
        "study-simulate-zero-participants",
        "prg-study",
        "simulate turing --participants 0 --true-rate 0.2 --out {tmp}/s.csv",
        2,
        "participants",
    ),
    case(
        "study-simulate-out-in-sys",
        "prg-study",
        "simulate turing --participants 3 --true-rate 0.2 --out /sys/prg/s.csv",
        2,
        "/sys/prg",
    ),
]

# Arguments every run of a command gets first (a case's own arguments come after and win).
COMMON = {
    "prg-prepare": ["data.augment.per_class=3", "workers=1", "progress=false", "figures=false"],
    "prg-train": ["paths.data_dir={data}", "trainer.max_epochs=1", "trainer.limit_train_batches=1"],
    "prg-evaluate": ["progress=false", "families=[cvae]", "models_dir={tmp}/models"],
    "prg-write": ["mlflow=false", "ckpt={ckpt}"],
    "prg-dictaphone": ["mlflow=false", "ckpt={ckpt}"],
    "prg-simulate": ["mlflow=false", "record=false", "progress=false", "ckpt={ckpt}"],
    "prg-study": [],
}


def test_the_table_covers_every_command_and_kind_of_input():
    assert len(CASES) >= 30 and len({c.id for c in CASES}) == len(CASES)
    commands = {c.command for c in CASES}
    assert commands == {*HYDRA_COMMANDS, "prg-study"}
    assert {c.code for c in CASES} == {1, 2}


# ---- bad files --------------------------------------------------------------------------------
def _png_header_only(path: Path, width: int, height: int) -> None:
    """A PNG whose header claims ``width`` x ``height`` grey pixels (no pixel data)."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        )

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IEND", b""))


def _wav(path: Path, samples: np.ndarray) -> None:
    with wave.open(str(path), "wb") as f:
        f.setnchannels(1), f.setsampwidth(2), f.setframerate(16000)
        f.writeframes(samples.astype(np.int16).tobytes())


def bad_files(tmp: Path, checkpoint: Path) -> dict[str, Path]:
    """The table's placeholders (but ``{tmp}``, each test's own folder), made under ``tmp``."""
    from PIL import Image

    from prg.sim import font_word

    rng = np.random.default_rng(0)
    files = {"ckpt": checkpoint, "data": tmp / "data", "turing": REPO / "conf/study/turing.yaml"}
    files["file"] = tmp / "a-file.txt"
    files["file"].write_text("a file, not a folder\n")
    files["folder"] = tmp / "a-folder"
    files["folder"].mkdir()
    files["text_ckpt"] = tmp / "notes.ckpt"
    files["text_ckpt"].write_text("not a checkpoint\n")
    files["truncated_ckpt"] = tmp / "truncated.ckpt"
    whole = checkpoint.read_bytes()
    files["truncated_ckpt"].write_bytes(whole[: len(whole) // 2])
    manifest = tmp / "data/prepared/synthetic/manifest.json"  # what prg-train reads first
    manifest.parent.mkdir(parents=True)
    manifest.write_text('{"source": "synthetic"}\n')
    files["garbage"] = tmp / "garbage.txt"
    files["garbage"].write_bytes(rng.integers(0, 256, 4000, dtype=np.uint8).tobytes())
    files["corrupt_wav"] = tmp / "corrupt.wav"
    files["corrupt_wav"].write_bytes(b"RIFF\x24\x00\x00\x00WAVEfmt " + rng.bytes(64))
    files["silent_wav"] = tmp / "silent.wav"
    _wav(files["silent_wav"], np.zeros(16000))
    files["empty_wav"] = tmp / "empty.wav"
    _wav(files["empty_wav"], np.zeros(0))
    files["text_png"] = tmp / "letters.png"
    files["text_png"].write_text("c a t\n")
    files["blank_png"] = tmp / "blank.png"
    Image.new("L", (120, 40), 255).save(files["blank_png"])
    files["huge_png"] = tmp / "huge.png"
    _png_header_only(files["huge_png"], 40000, 40000)
    files["noise_jpg"] = tmp / "photo.png"  # a JPEG photo of noise under a PNG name
    noise = rng.integers(0, 256, (60, 200, 3), dtype=np.uint8)
    Image.fromarray(noise).save(files["noise_jpg"], format="JPEG")
    files["word"] = font_word("ok").to_json(tmp / "word.json")
    files["bad_json"] = tmp / "bad.json"
    files["bad_json"].write_text("{not json")
    files["bad_yaml"] = tmp / "bad.yaml"
    files["bad_yaml"].write_text("name: [turing\nkind: {\n")
    files["bad_csv"] = tmp / "responses.csv"
    files["bad_csv"].write_bytes(b'participant,"word\n\x00\x01,"x\n')
    return files


@pytest.fixture(scope="module")
def shared(tmp_path_factory, untrained_muse_checkpoint) -> tuple[Path, dict[str, Path]]:
    """The bad files, made once: their folder and the placeholders."""
    folder = tmp_path_factory.mktemp("bad-files")
    return folder, bad_files(folder, untrained_muse_checkpoint)


# ---- running a command in this process ---------------------------------------------------------
def entry_point(command: str):
    """The function the installed console script ``command`` calls."""
    (point,) = importlib.metadata.entry_points(group="console_scripts", name=command)
    return point.load()


@pytest.fixture
def restore_logging():
    """Hydra configures the root logger for each run; put it back as it was."""
    root = logging.getLogger()
    handlers, level = list(root.handlers), root.level
    yield
    for handler in root.handlers:
        if handler not in handlers:
            handler.close()
    root.handlers[:] = handlers
    root.setLevel(level)


def argv_of(c: Case, files: dict[str, Path], tmp: Path) -> list[str]:
    """The command line of case ``c`` run in the folder ``tmp``."""
    args = [*COMMON[c.command], *c.args]
    if c.command in HYDRA_COMMANDS:
        args = [f"paths.root_dir={tmp}", f"paths.log_dir={tmp / LOGS}", *args]
    return [a.format(tmp=tmp, **files) for a in args]


LOGS = "hydra-logs"  # Hydra's own run folders: the one thing a failed command may leave


def snapshot(*folders: Path) -> dict[Path, tuple[int, int]]:
    """Every file under ``folders`` (but Hydra's ``LOGS``) with its size and mtime. Folders are
    left out: a staging folder made and removed changes its parent's mtime, and an empty
    download cache folder (``data/raw/uji``) is no partial output."""
    found = {}
    for folder in folders:
        for dirpath, dirnames, filenames in os.walk(folder):
            dirnames[:] = [d for d in dirnames if d != LOGS]
            for name in filenames:
                stat = Path(dirpath, name).lstat()
                found[Path(dirpath, name)] = (stat.st_size, stat.st_mtime_ns)
    return found


def check_result(c: Case, code, out: str, err: str) -> None:
    assert "Traceback" not in out + err, err[-3000:]
    lines = err.strip().splitlines()
    assert len(lines) == 1, err[-3000:]
    assert lines[0].startswith(f"{c.command}: error: "), lines[0]
    assert c.expected in lines[0], lines[0]
    assert code == c.code, (code, lines[0])


@pytest.mark.parametrize("c", CASES, ids=[c.id for c in CASES])
def test_bad_input_is_one_line_with_its_exit_code_and_writes_nothing(
    c, tmp_path, shared, monkeypatch, capfd, restore_logging
):
    folder, files = shared
    monkeypatch.chdir(tmp_path)  # default (relative) outputs land where the snapshot looks
    before = snapshot(tmp_path, folder)
    monkeypatch.setattr(sys, "argv", [c.command, *argv_of(c, files, tmp_path)])
    capfd.readouterr()
    try:
        code = entry_point(c.command)()
    except SystemExit as exit:
        code = exit.code
    out, err = capfd.readouterr()
    check_result(c, code, out, err)
    assert snapshot(tmp_path, folder) == before


SUBPROCESS = ["simulate-word-too-large", "study-build-out-below-file"]  # one per kind of CLI


@pytest.mark.parametrize("id", SUBPROCESS)
def test_console_scripts_behave_the_same(id, tmp_path, shared):
    (c,) = [c for c in CASES if c.id == id]
    folder, files = shared
    before = snapshot(tmp_path, folder)
    result = run_cli(c.command, *argv_of(c, files, tmp_path), cwd=tmp_path)
    check_result(c, result.returncode, result.stdout, result.stderr)
    assert snapshot(tmp_path, folder) == before


def _write_to_a_full_disk(cfg) -> None:
    Path("/dev/full").write_text("a result")  # the kernel's always-full device: ENOSPC


def _a_bug(cfg) -> None:
    {}["missing"]  # a programming error, not bad input


@pytest.mark.parametrize(
    "task, one_line", [(_write_to_a_full_disk, True), (_a_bug, False)], ids=["disk-full", "bug"]
)
def test_a_full_disk_is_one_line_exit_1_but_a_bug_keeps_its_traceback(
    task, one_line, tmp_path, monkeypatch, capfd, restore_logging
):
    from prg.cli import hydra_command

    main = hydra_command(task, "prepare", "prg-x")
    monkeypatch.setattr(sys, "argv", ["prg-x", f"paths.root_dir={tmp_path}"])
    capfd.readouterr()
    with pytest.raises(SystemExit) as exit:
        main()
    err = capfd.readouterr().err
    assert exit.value.code == 1
    if one_line:
        assert err.strip().splitlines() == ["prg-x: error: No space left on device"]
    else:
        assert "Traceback" in err and "KeyError: 'missing'" in err
