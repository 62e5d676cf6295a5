"""SIGTERM and SIGINT to every command: exit 128 + signal with one line, the previous outputs as
they were, no process of the command left running, no hidden staging folder left behind.

Real processes and real signals. A command is signalled once its handler is installed (its
``SigCgt`` mask in ``/proc`` shows SIGTERM caught; before that the interpreter is still
importing and the default action, death by the signal, is the right one) and, where a test says
so, once the work is visibly under way (pool workers started, a checkpoint written).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.conftest import BIN, small_data_cfg

TERM_BIT = 1 << (signal.SIGTERM - 1)


def _caught(pid: int) -> int:
    """The process's caught-signals mask (0 when it is gone)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return 0
    line = next(line for line in status.splitlines() if line.startswith("SigCgt:"))
    return int(line.split()[1], 16)


def _descendants(pid: int) -> set[int]:
    """Every running process below ``pid`` (zombies excluded), found through /proc."""
    parents: dict[int, int] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        fields = stat[stat.rfind(")") + 2 :].split()
        if fields[0] != "Z":
            parents[int(entry.name)] = int(fields[1])
    found, frontier = set(), {pid}
    while frontier:
        frontier = {p for p, parent in parents.items() if parent in frontier} - found
        found |= frontier
    return found


def _alive(pids: set[int]) -> set[int]:
    alive = set()
    for pid in pids:
        try:
            state = Path(f"/proc/{pid}/stat").read_text()
        except OSError:
            continue
        if state[state.rfind(")") + 2] != "Z":
            alive.add(pid)
    return alive


def _tree_hashes(*roots: Path) -> dict[str, str]:
    out = {}
    for root in roots:
        for path in sorted(root.rglob("*")) if root.is_dir() else [root]:
            if path.is_file():
                out[str(path)] = hashlib.sha256(path.read_bytes()).hexdigest()
    return out


def _leftovers(*folders: Path) -> list[Path]:
    return [
        p
        for folder in folders
        for p in (folder.rglob(".*") if folder.is_dir() else [])
        if ".tmp-" in p.name or ".old-" in p.name
    ]


def signal_command(
    argv: list[str],
    sig: signal.Signals,
    cwd: Path,
    ready: Callable[[int], bool] = lambda pid: True,
    timeout: float = 240,
) -> tuple[int, str, set[int]]:
    """Start ``argv``, wait for its handler and ``ready(pid)``, send ``sig``; returns the exit
    code, stderr and the processes below it that still run 10 s after it ended."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "PRG_ROOT": str(cwd)}
    proc = subprocess.Popen(
        argv, cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
    )
    try:
        deadline = time.monotonic() + timeout
        while not (_caught(proc.pid) & TERM_BIT and ready(proc.pid)):
            assert proc.poll() is None, f"ended before the signal: {proc.stderr.read()[-2000:]}"
            assert time.monotonic() < deadline, "never got ready"
            time.sleep(0.05)
        below = _descendants(proc.pid)
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=120)
        grace = time.monotonic() + 10
        while _alive(below) and time.monotonic() < grace:
            time.sleep(0.1)
        return proc.returncode, err, _alive(below)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def check(code: int, err: str, left: set[int], command: str, sig: signal.Signals) -> None:
    lines = err.strip().splitlines()
    assert code == 128 + sig, err[-3000:]
    assert lines == [
        f"{command}: error: stopped by {sig.name}; the outputs of earlier runs are left as they were"
    ], err[-3000:]
    assert not left, f"processes left running: {left}"


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    from prg.data.build import build_dataset

    data_dir = tmp_path_factory.mktemp("signal-data")
    build_dataset(small_data_cfg(), data_dir, workers=1, progress=False, figures=True)
    return data_dir


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_prepare_stopped_while_its_workers_fit(tmp_path, dataset, sig):
    """Workers running: they are stopped, the old dataset and metrics file stay byte for byte."""
    data_dir = tmp_path / "data"
    shutil.copytree(dataset / "prepared" / "synthetic", data_dir / "prepared" / "synthetic")
    metrics = tmp_path / "metrics.json"
    metrics.write_text('{"old": true}\n')
    before = _tree_hashes(data_dir / "prepared" / "synthetic", metrics)
    argv = [
        str(BIN / "prg-prepare"),
        f"paths.root_dir={tmp_path}",
        f"paths.data_dir={data_dir}",
        "data.synthetic.n_writers=40",
        "data.augment.per_class=200",
        "workers=2",
        "progress=false",
        f"metrics_path={metrics}",
    ]
    code, err, left = signal_command(argv, sig, tmp_path, lambda pid: len(_descendants(pid)) >= 4)
    check(code, err, left, "prg-prepare", sig)
    assert _tree_hashes(data_dir / "prepared" / "synthetic", metrics) == before
    assert not _leftovers(data_dir / "prepared", tmp_path)


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_train_stopped_mid_epoch(tmp_path, dataset, sig):
    """Inside Lightning's fit (whose own SIGTERM handler would exit 0), DataLoader workers on."""
    export = tmp_path / "export"
    export.mkdir()
    (export / "model.ckpt").write_bytes(b"the previous export")
    (export / "metrics.json").write_text('{"old": true}\n')
    before = _tree_hashes(export)
    ckpt_dir = tmp_path / "ckpt"
    argv = [
        str(BIN / "prg-train"),
        f"paths.root_dir={tmp_path}",
        f"paths.data_dir={dataset}",
        "model=cvae",
        "model.batch_size=16",
        "trainer.max_epochs=100",
        "trainer.enable_progress_bar=false",
        "callbacks.figures=null",
        "callbacks.last.every_n_train_steps=2",
        "data.loader.num_workers=2",
        f"checkpoint_dir={ckpt_dir}",
        f"export_dir={export}",
    ]
    code, err, left = signal_command(
        argv, sig, tmp_path, lambda pid: (ckpt_dir / "last.ckpt").exists()
    )
    check(code, err, left, "prg-train", sig)
    assert _tree_hashes(export) == before
    assert not _leftovers(export, ckpt_dir)


def _evaluate(tmp, dataset, checkpoint):
    return [
        str(BIN / "prg-evaluate"),
        f"paths.root_dir={tmp}",
        f"paths.data_dir={dataset}",
        "parts=[classifiers]",
    ]


def _write(tmp, dataset, checkpoint):
    return [
        str(BIN / "prg-write"),
        f"paths.root_dir={tmp}",
        "text=signals",
        f"ckpt={checkpoint}",
        f"out_dir={tmp}/out",
    ]


def _dictaphone(tmp, dataset, checkpoint):
    return [
        str(BIN / "prg-dictaphone"),
        f"paths.root_dir={tmp}",
        f"paths.data_dir={dataset}",
        "words=[cat,jump]",
        "speech.lexicon=[bell,cat,jump]",
        f"ckpt={checkpoint}",
        f"out_dir={tmp}/out",
        "mlflow=false",
    ]


def _simulate(tmp, dataset, checkpoint):
    return [
        str(BIN / "prg-simulate"),
        f"paths.root_dir={tmp}",
        "text=ok",
        f"ckpt={checkpoint}",
        f"out_dir={tmp}/out",
        "progress=false",
    ]


def _export(tmp, dataset, checkpoint):
    from prg.sim import font_word

    word = font_word("ok").to_json(tmp / "word.json")
    return [str(BIN / "prg-export"), f"paths.root_dir={tmp}", f"word={word}", f"out_dir={tmp}/out"]


def _study(tmp, dataset, checkpoint):
    return [
        str(BIN / "prg-study"),
        "simulate",
        "turing",
        "--participants",
        "400",
        "--true-rate",
        "0.5",
        "--out",
        f"{tmp}/out/responses.csv",
    ]


def _paper_scale(tmp, dataset, checkpoint):
    return [
        sys.executable,
        "-m",
        "prg.commands.paper_scale",
        "--profile",
        "converged",
        "--root",
        str(tmp / "out"),
        "--data-dir",
        str(dataset),
        "--device",
        "cpu",
        "--families",
        "cvae",
    ]


COMMANDS = {
    "prg-evaluate": _evaluate,
    "prg-write": _write,
    "prg-dictaphone": _dictaphone,
    "prg-simulate": _simulate,
    "prg-export": _export,
    "prg-study": _study,
    "prg.commands.paper_scale": _paper_scale,
}


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
@pytest.mark.parametrize("command", list(COMMANDS))
def test_every_command_stops_on_a_signal(
    command, sig, tmp_path, dataset, untrained_muse_checkpoint
):
    out = tmp_path / "out"
    out.mkdir()
    (out / "previous.txt").write_text("an earlier run's output\n")
    before = _tree_hashes(out, tmp_path / "models")
    argv = COMMANDS[command](tmp_path, dataset, untrained_muse_checkpoint)
    ready = (lambda pid: bool(_descendants(pid))) if command == "prg.commands.paper_scale" else None
    code, err, left = signal_command(argv, sig, tmp_path, ready or (lambda pid: True))
    check(code, err, left, command, sig)
    after = {k: v for k, v in _tree_hashes(out, tmp_path / "models").items() if "/logs/" not in k}
    assert after == before  # logs (paper_scale's per-job logs) are not outputs
    assert not _leftovers(tmp_path)


def test_a_signal_during_config_composition_waits_for_the_task(monkeypatch, capsys, tmp_path):
    """A signal that lands while Hydra composes the config is held (OmegaConf's cleanup code can
    swallow an exception raised inside it) and stops the command as the task starts."""
    from prg.commands import cli
    from prg.commands import preflight as checks_first

    ran = []

    def preflight(command, config_name, argv):
        os.kill(os.getpid(), signal.SIGTERM)  # arrives inside the composition
        ran.append("preflight went on")

    monkeypatch.setattr(checks_first, "preflight", preflight)
    monkeypatch.setattr(sys, "argv", ["prg-write", f"hydra.run.dir={tmp_path}/logs"])
    main = cli.hydra_command(lambda cfg: ran.append("task ran"), "write", "prg-write")
    with pytest.raises(SystemExit) as stopped:
        main()
    assert stopped.value.code == 128 + signal.SIGTERM
    assert ran == ["preflight went on"]  # held through the composition, raised before the task
    assert "stopped by SIGTERM" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv", [["prg-evaluate", "--help"], ["prg-study", "power", "turing"]], ids=["hydra", "study"]
)
def test_a_reader_that_goes_away_ends_the_command_quietly_as_sigpipe_would(tmp_path, argv):
    """``prg-evaluate --help | head -1``: the pipe's reader is gone before the command writes."""
    read_end, write_end = os.pipe()
    os.close(read_end)  # no reader: the command's first write fails with EPIPE
    try:
        result = subprocess.run(
            [str(BIN / argv[0]), *argv[1:]],
            stdout=write_end,
            stderr=subprocess.PIPE,
            text=True,
            cwd=tmp_path,
            env={**os.environ, "PRG_ROOT": str(tmp_path)},
            timeout=120,
        )
    finally:
        os.close(write_end)
    assert result.returncode == 128 + signal.SIGPIPE, result.stderr[-2000:]
    assert result.stderr == ""  # no traceback, no line: a shell tool says nothing either
