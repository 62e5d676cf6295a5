"""A word's Rerun recording made in a second process, started before the command loads its model.

Importing Rerun (with the pandas that pyarrow pulls in when Rerun first converts an array) and
writing ``word.rrd`` cost ``prg-write`` about as much as all its other work. A
:class:`RecorderProcess` pays the imports on the second CPU core while the command imports torch
and decodes the word, then records the word while the command writes its other files.

Protocol: the parent starts ``python -m prg.recorder``, which imports and then reads one
line from its standard input: a folder holding ``word.json`` (the word) and
``.recording.npz`` (the rollout and the inputs, plain arrays read without pickle). It writes
``word.rrd`` into that folder through :func:`prg.recording.record_write`, the same function a
recording made in the parent's own process goes through (:meth:`prg.writer.WriteResult.record`),
and prints ``recorded``; otherwise it exits with a one-line message (code 2 for bad input).
"""

from __future__ import annotations

import signal
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from prg.errors import PRGError, UsageError

REQUEST = ".recording.npz"  # beside word.json in the folder the worker is sent
_OPTIONAL = ("letters", "images", "audio")


def write_request(folder: Path, rollout: np.ndarray, inputs: dict[str, Any]) -> Path:
    """Save the arrays a recording needs besides ``word.json`` into ``folder``: the rollout and
    those of ``letters``, ``images``, ``audio``, ``sample_rate``, ``transcript`` that are given."""
    arrays: dict[str, np.ndarray] = {"rollout": np.asarray(rollout)}
    for name in _OPTIONAL:
        if inputs.get(name) is not None:
            arrays[name] = np.asarray(inputs[name])
    if inputs.get("transcript") is not None:
        arrays["transcript"] = np.array(inputs["transcript"], dtype=np.str_)
        arrays["sample_rate"] = np.array(int(inputs["sample_rate"]))
    path = folder / REQUEST
    np.savez(path, **arrays)
    return path


def record_request(folder: Path) -> Path:
    """Write ``folder/word.rrd`` from ``folder/word.json`` and the request beside it."""
    from prg.pipeline.word import WordTrajectory
    from prg.recording import record_write

    word = WordTrajectory.from_json(folder / "word.json")
    with np.load(folder / REQUEST, allow_pickle=False) as request:
        kwargs: dict[str, Any] = {name: request[name] for name in _OPTIONAL if name in request}
        if "transcript" in request:
            kwargs["transcript"] = str(request["transcript"])
            kwargs["sample_rate"] = int(request["sample_rate"])
        rollout = request["rollout"]
    return record_write(folder / "word.rrd", word, rollout, **kwargs)


class RecorderProcess:
    """The worker process (module docstring); a context manager that stops it on the way out.

    ``send(folder, rollout, inputs)`` once the word is in ``folder``, then ``wait()`` for
    ``word.rrd``; a failure there raises the worker's one-line message as a
    :class:`~prg.errors.PRGError` (:class:`~prg.errors.UsageError` for bad input).
    """

    def __init__(self) -> None:
        # the worker's stderr (a pipe could fill up); closed in close()
        self._errors = tempfile.TemporaryFile("w+", encoding="utf-8")  # noqa: SIM115
        self._process = subprocess.Popen(
            [sys.executable, "-m", "prg.recorder"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self._errors,
            text=True,
        )
        self._request: Path | None = None

    def send(self, folder: Path, rollout: np.ndarray, inputs: dict[str, Any]) -> None:
        self._request = write_request(folder, rollout, inputs)
        assert self._process.stdin is not None
        self._process.stdin.write(f"{folder}\n")
        self._process.stdin.flush()

    def wait(self, timeout_s: float = 300) -> None:
        """Until ``word.rrd`` is written (the worker's ``recorded`` line), or raise its error."""
        assert self._process.stdout is not None and self._process.stdin is not None
        self._process.stdin.close()
        done = self._process.stdout.readline().strip() == "recorded"
        if self._request is not None:
            self._request.unlink(missing_ok=True)
        if done:
            return
        self._process.wait(timeout=timeout_s)
        self._errors.seek(0)
        lines = self._errors.read().strip().splitlines() or ["(no message)"]
        message = f"the recording (word.rrd) failed: {lines[-1]}"
        raise UsageError(message) if self._process.returncode == 2 else PRGError(message)

    def close(self) -> None:
        """Stop the worker if it still runs (its recording, if any, is already on disk)."""
        if self._process.poll() is None:
            self._process.kill()
        self._process.wait()
        for stream in (self._process.stdin, self._process.stdout, self._errors):
            if stream is not None and not stream.closed:
                stream.close()

    def __enter__(self) -> RecorderProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def warm_up() -> None:
    """Import what a recording needs and write a small one to a temporary folder: Rerun's first
    recording in a process costs about ten times the next (lazy imports and set-up inside
    Rerun), and this runs while the parent is still loading its model."""
    import pandas  # noqa: F401  (pyarrow imports it at Rerun's first array conversion)

    from prg.pipeline.word import assemble_word
    from prg.recording import record_write

    turn = np.linspace(0.0, 2.0 * np.pi, 50)
    loop = np.column_stack([np.sin(turn), np.cos(turn)])
    word = assemble_word(
        [loop, loop + np.array([3.0, 0.0])], [np.array([[1.0, 0.0], [2.0, 0.0]])], "oo"
    )
    with tempfile.TemporaryDirectory(prefix="prg-recorder-") as folder:
        record_write(Path(folder) / "warm.rrd", word, word.points, letters=np.stack([loop, loop]))


def main() -> int:
    # the parent decides what a Ctrl-C stops (it stops this process on its way out)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    warm_up()
    line = sys.stdin.readline().strip()
    if not line:  # the parent stopped before sending a word
        return 0
    try:
        record_request(Path(line))
    except UsageError as err:
        print(err, file=sys.stderr)
        return 2
    print("recorded", flush=True)  # the parent goes on; Rerun's shutdown is not waited for
    return 0


if __name__ == "__main__":
    sys.exit(main())
