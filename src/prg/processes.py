"""Child processes run concurrently, their output shown line by line with their name in front.

A :class:`Job` is one child's command line, log file and environment. :func:`run_stage` starts
the jobs of one stage together and waits for all of them; the first one that fails stops the
others (:func:`stop`: SIGINT to each process group, SIGKILL after :data:`STOP_GRACE_S`) and raises
:class:`StageFailed` with one line naming it, its last error line and its log. A handled signal
(:class:`prg.signals.Interrupted`) stops them the same way.

Each child's whole output goes to its log. On the terminal (:class:`Console`) every line is
prefixed with the job's name (``[muse] ...``); a progress bar (tqdm's, redrawn with carriage
returns) is kept aside, shortened, and shown at most every ``progress_every`` seconds.
``python -m prg.commands.paper_scale`` runs its trainings and evaluation this way.
"""

from __future__ import annotations

import contextlib
import os
import re
import shlex
import signal
import subprocess
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path

from prg.errors import PRGError
from prg.signals import Interrupted, deferred

__all__ = [
    "STOP_GRACE_S",
    "Console",
    "Job",
    "StageFailed",
    "duration",
    "run_stage",
    "start",
    "stop",
]

# Seconds a stopped process gets to shut down after SIGINT before it is killed.
STOP_GRACE_S = 10.0

_PROGRESS = re.compile(r"\d+/(\d+|\?) \[|\d+%\|")
_ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")
# Lines not worth a terminal line (still in the log): an advertisement, a warning every epoch.
_NOISE = ("💡 Tip:", "`weights_only` was not set")
_ERROR_LINE = re.compile(r"^(prg-\w+: error: |[A-Za-z_][\w.]*(Error|Exception|Interrupt)\b)")


@dataclass
class Job:
    """One child process: its command, log file, output tail and wall time."""

    name: str
    argv: list[str]
    log: Path
    env: dict[str, str]
    proc: subprocess.Popen | None = None
    started: float = 0.0
    ended: float | None = None
    lines: deque = field(default_factory=lambda: deque(maxlen=200))
    progress: str = ""
    shown: str = ""
    reader: threading.Thread | None = None

    @property
    def seconds(self) -> float:
        return round((self.ended or time.perf_counter()) - self.started, 2)

    def error_line(self) -> str:
        """The child's last error line (``prg-train: error: ...``, ``ValueError: ...``)."""
        lines = [line for line in self.lines if line.strip()]
        for line in reversed(lines):
            if _ERROR_LINE.match(line.strip()):
                return line.strip()
        useful = [line for line in lines if "HYDRA_FULL_ERROR" not in line]
        return useful[-1].strip() if useful else "no output"


class Console:
    """Prints the children's lines with their name in front, one writer at a time."""

    def __init__(self) -> None:
        self.lock = threading.Lock()

    def say(self, text: str, prefix: str = "") -> None:
        with self.lock:
            print(f"[{prefix}] {text}" if prefix else text, flush=True)


def _short_bar(text: str) -> str:
    """A tqdm line without its bar glyphs: ``Epoch 3:  45% 500/1099 [00:10<00:12, ...]``."""
    return re.sub(r"\|[^|]*\|", " ", text).strip()


def _take(job: Job, console: Console, raw: bytes) -> None:
    """One piece of the child's output: a progress bar is kept for later, a line printed."""
    text = _ANSI.sub("", raw.decode("utf-8", "replace")).rstrip()
    bar = _PROGRESS.search(text)
    if bar:  # a bar, perhaps with a warning written right after it
        close = text.find("]", bar.end())
        job.progress = _short_bar(text if close < 0 else text[: close + 1])
        text = "" if close < 0 else text[close + 1 :]
    text = text.strip()
    if text and not text.startswith(_NOISE):
        job.lines.append(text)
        console.say(text, job.name)


def _pump(job: Job, console: Console) -> None:
    """Copy the child's output to its log and take it apart at carriage returns and newlines."""
    assert job.proc is not None and job.proc.stdout is not None
    buffer = b""
    with open(job.log, "ab") as log:
        while chunk := job.proc.stdout.read1(65536):
            log.write(chunk)
            log.flush()
            *parts, buffer = re.split(rb"[\r\n]", buffer + chunk)
            for raw in parts:
                _take(job, console, raw)
        _take(job, console, buffer)


def start(job: Job, console: Console) -> None:
    """Start ``job``'s process in its own session, its output read into its log and onto the
    console by a thread; the log starts with the command line, the console line with the command
    after ``python -m``."""
    job.log.parent.mkdir(parents=True, exist_ok=True)
    job.log.write_text(f"$ {shlex.join(job.argv)}\n")
    console.say(f"start: {shlex.join(job.argv[2:])}", job.name)
    job.started = time.perf_counter()
    with deferred():  # a signal here would leave a child that `stop` does not know of
        job.proc = subprocess.Popen(
            job.argv,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL,
            env=job.env,
            start_new_session=True,  # its own process group: stopped as a whole, workers too
        )
    job.reader = threading.Thread(target=_pump, args=(job, console), daemon=True)
    job.reader.start()


def stop(jobs: list[Job]) -> list[str]:
    """Interrupt every running job's process group, kill what is left after a grace period;
    returns the names of the jobs that were still running."""
    running = [j for j in jobs if j.proc is not None and j.proc.poll() is None]
    for job in running:
        with contextlib.suppress(ProcessLookupError):  # Lightning shuts down, MLflow run KILLED
            os.killpg(job.proc.pid, signal.SIGINT)
    deadline = time.monotonic() + STOP_GRACE_S
    for job in running:
        with contextlib.suppress(subprocess.TimeoutExpired):
            job.proc.wait(timeout=max(0.1, deadline - time.monotonic()))
    for job in running:
        with contextlib.suppress(ProcessLookupError):  # also any worker left in the group
            os.killpg(job.proc.pid, signal.SIGKILL)
        job.proc.wait()
        job.ended = job.ended or time.perf_counter()
    return [j.name for j in running]


class StageFailed(PRGError):
    """A child process failed; carries the exit code to pass on (2 for its usage errors)."""

    def __init__(self, message: str, code: int):
        super().__init__(message)
        self.exit_code = code


def run_stage(stage: str, jobs: list[Job], console: Console, progress_every: float) -> None:
    """Run ``jobs`` concurrently to the end; the first failure stops the others."""
    last_shown = time.monotonic()
    try:
        for job in jobs:
            start(job, console)
        while True:
            pending = [j for j in jobs if j.ended is None]
            for job in pending:
                code = job.proc.poll()
                if code is None:
                    continue
                job.reader.join(timeout=5)  # a grandchild may hold the pipe open a moment
                job.ended = time.perf_counter()
                if code != 0:
                    stopped = stop(jobs)
                    raise StageFailed(
                        f"{stage}: {job.name} failed "
                        + (f"(exit {code})" if code > 0 else f"(killed by signal {-code})")
                        + f": {job.error_line()}"
                        + (f"; stopped {', '.join(stopped)}" if stopped else "")
                        + f"; log: {job.log}",
                        2 if code == 2 else 1,
                    )
                if job.progress and job.progress != job.shown:  # its last state, e.g. val/loss
                    job.shown = job.progress
                    console.say(job.progress, job.name)
                console.say(f"done in {duration(job.seconds)}", job.name)
            if all(j.ended is not None for j in jobs):
                return
            if time.monotonic() - last_shown >= progress_every:
                last_shown = time.monotonic()
                for job in jobs:
                    if job.ended is None and job.progress and job.progress != job.shown:
                        job.shown = job.progress
                        console.say(job.progress, job.name)
            time.sleep(0.2)
    except Interrupted:
        stopped = stop(jobs)
        console.say(f"{stage}: interrupted; stopped {', '.join(stopped) or 'nothing'}")
        raise


def duration(seconds: float) -> str:
    """``seconds`` for people: ``12.3 s``, or ``4 m 05 s`` from a minute on."""
    minutes, secs = divmod(round(seconds), 60)
    return f"{minutes} m {secs:02d} s" if minutes else f"{seconds:.1f} s"
