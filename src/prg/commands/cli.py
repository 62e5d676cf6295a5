"""Thin Hydra entry points with one-line errors.

Every ``prg-*`` command is ``hydra_command(task, config_name, command)``. Before Hydra runs, the
command line is composed once against ``conf/`` (:mod:`prg.commands.preflight`) so that an unknown config group, a typo in a key
or a malformed override is reported as one line with exit code 2 instead of Hydra's multi-line
message, and so is an interpolation that cannot be resolved (``${oc.env:NOPE}``); Hydra's log
folder (``paths.log_dir``) is checked there too. Each task then checks its numeric options
against :data:`prg.checks.RANGES` (:func:`prg.checks.check_values`). Inside the task,
:class:`prg.errors.PRGError` becomes ``<command>: error: <message>`` with its exit code (2 for
usage errors, 1 for run-time failures); an :class:`OSError` about a file or the disk (no space,
read-only, permission, I/O error) is a run-time failure naming the path (exit 1). Any other
exception is a bug and keeps its traceback.

Signals: SIGINT (Ctrl-C), SIGTERM (``kill``, SLURM, container managers) and SIGHUP end every
command the same way (:func:`handle_signals`): the work stops, child processes are terminated,
every output is left as it was before the command (outputs are staged, :mod:`prg.files`), and
one line ``<command>: error: stopped by SIGTERM ...`` is printed with exit code 128 + the signal
number (130 for SIGINT, 143 for SIGTERM), the shell's convention. A second signal while the
first is being handled ends the process at once.

Tasks call :func:`check_output` on every output path before they start working, so a path that
cannot be written is a usage error (exit 2) before anything is computed or written.

The project root (``paths.root_dir``: data, models, reports, outputs, logs, the MLflow store) is
:func:`project_root`, through the ``${prg.root:}`` resolver, so a command works the same from
any folder and writes nothing into the working folder unless asked. The command line is checked
(keys, numeric ranges, choices, :mod:`prg.checks`) before the command's task runs; a command
module that imports its heavy libraries (torch, Lightning, MLflow ...) inside its task, as
``prg-write`` does, answers a bad command line before loading them.
"""

from __future__ import annotations

import contextlib
import errno
import logging
import os
import signal
import sys
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, NoReturn

import tomllib
from omegaconf import OmegaConf

from prg.errors import PRGError, UsageError
from prg.resources import config_dir
from prg.signals import Interrupted, hold, raising_signals, release, stop_children

ROOT_ENV = "PRG_ROOT"


def is_project_root(folder: Path) -> bool:
    """Whether ``folder`` is a checkout of this project: ``dvc.yaml`` (the pipeline whose outputs
    live under it) next to a ``pyproject.toml`` whose ``[project]`` is named ``prg`` (a
    ``dvc.yaml`` alone would also match other DVC projects)."""
    if not (folder / "dvc.yaml").is_file():
        return False
    try:
        with (folder / "pyproject.toml").open("rb") as file:
            project = tomllib.load(file).get("project")
    except (OSError, tomllib.TOMLDecodeError):
        return False
    return isinstance(project, dict) and project.get("name") == "prg"


def project_root() -> tuple[Path, str]:
    """The project root (absolute) and where it came from, in this order:

    1. ``PRG_ROOT``, when set;
    2. the nearest folder from the working folder upward that is a checkout of the project
       (:func:`is_project_root`);
    3. the checkout the running code is installed from (an editable install, ``make setup``);
    4. ``$XDG_DATA_HOME/prg`` (``~/.local/share/prg``).

    Never the working folder itself by default: nothing is written there unless asked.
    """
    given = os.environ.get(ROOT_ENV)
    if given:
        return Path(given).expanduser().absolute(), ROOT_ENV
    here = Path.cwd()
    for folder in (here, *here.parents):
        if is_project_root(folder):
            return folder, "found above the working folder"
    code = Path(__file__).resolve().parents[3]  # <checkout>/src/prg/commands/cli.py
    if is_project_root(code):
        return code, "the code's checkout, no project above the working folder"
    data = Path(os.environ.get("XDG_DATA_HOME") or Path.home() / ".local/share") / "prg"
    return data, "the default, no project above the working folder"


def describe_root(root_dir: str | os.PathLike) -> str:
    """``project root <root_dir>: <where it came from>``, for messages about missing inputs."""
    root, origin = project_root()
    if Path(root_dir).absolute() != root:
        origin = "paths.root_dir"
    return f"project root {Path(root_dir).absolute()}: {origin}"


# conf/paths/default.yaml: ``root_dir: ${prg.root:}``; cached per config, so one run sees one root
OmegaConf.register_new_resolver("prg.root", lambda: str(project_root()[0]), use_cache=True)


def fail(command: str, message: str, code: int) -> None:
    """Print one line to stderr and exit."""
    print(f"{command}: error: {message}", file=sys.stderr)
    sys.exit(code)


def check_output(path: str | os.PathLike, key: str, *, folder: bool = True) -> Path:
    """``path`` if an output folder (or, ``folder=False``, a file) can be written there.

    The nearest existing folder on the way is probed by creating and removing an empty folder in
    it, which also catches what file modes do not tell root (a read-only or pseudo file system
    such as ``/sys``). Nothing is left behind.

    Raises
    ------
    UsageError
        Naming ``key`` and the path: it exists but is of the wrong kind, a file stands where a
        folder must be, or the folder refuses new entries.
    """
    path = Path(path)
    kind = "a folder" if folder else "a regular file"
    _check_links(path, key, kind)
    if path.exists() and (path.is_dir() != folder or not (folder or path.is_file())):
        raise UsageError(f"{key} {path}: exists and is not {kind}")
    existing = path if folder else path.parent
    while not existing.exists():  # also False below a regular file
        existing = existing.parent
    if not existing.is_dir():
        raise UsageError(f"{key} {path}: {existing} is a file, not a folder")
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".prg-probe-", dir=existing))
    except OSError as err:
        raise UsageError(f"{key} {path}: cannot write in {existing} ({err.strerror})") from None
    return path


def _check_links(path: Path, key: str, kind: str) -> None:
    """Refuse ``path`` when it or a folder above it is a symbolic link that loops or points to
    nothing: the output could never be written there (``mkdir`` would say "File exists")."""
    for part in (path, *path.parents):
        if not part.is_symlink():
            continue
        try:
            os.stat(part)
        except OSError as err:
            problem = "loops" if err.errno == errno.ELOOP else "points to nothing"
            if err.errno not in (errno.ELOOP, errno.ENOENT):
                problem = f"cannot be followed ({err.strerror})"
            raise UsageError(
                f"{key} {path}: {part} is a symbolic link that {problem}; accepted: {kind} or "
                "a link to one"
            ) from None


# OSErrors that are about the machine, not the code, even without a file name.
_ENVIRONMENT_ERRNOS = {
    errno.ENOSPC,
    errno.EDQUOT,
    errno.EROFS,
    errno.EIO,
    errno.EACCES,
    errno.EPERM,
}


# What to do about an OSError of the machine, by errno
_ADVICE = {
    errno.ENOSPC: "free space on that disk, or write elsewhere",
    errno.EDQUOT: "free space within your disk quota, or write elsewhere",
    errno.EFBIG: "over this process's file size limit: raise it (ulimit -f)",
    errno.EROFS: "the file system is read-only: write elsewhere",
    errno.EACCES: "make it writable for this user, or write elsewhere",
    errno.EPERM: "make it writable for this user, or write elsewhere",
}


def os_error_message(err: OSError) -> str | None:
    """One line for an OSError about a named file or the disk (with what to do about the disk,
    :data:`_ADVICE`); None for any other OSError."""
    if err.filename is None and err.errno not in _ENVIRONMENT_ERRNOS:
        return None
    reason = err.strerror or str(err)
    advice = f" ({_ADVICE[err.errno]})" if err.errno in _ADVICE else ""
    if err.filename is None:
        return f"{reason}{advice}"
    names = f"{err.filename} -> {err.filename2}" if err.filename2 else str(err.filename)
    return f"{names}: {reason}{advice}"


# An MLflow store's database refusing a write: (words of the database's error, the problem)
_STORE_PROBLEMS = (
    ("readonly database", "is read-only"),
    ("read-only", "is read-only"),
    ("database or disk is full", "cannot grow: its disk is full"),
    ("disk i/o error", "cannot be written (disk I/O error)"),
    ("unable to open database file", "cannot be opened"),
)


def store_error_message(err: BaseException, cfg: Any) -> str | None:
    """One line for an MLflow store (``logger.tracking_uri``, ``MLFLOW_TRACKING_URI``) that
    refuses to be written, naming the store and what to do; None for any other error."""
    chain: list[BaseException] = []
    seen: BaseException | None = err
    while seen is not None and len(chain) < 10:
        chain.append(seen)
        seen = seen.__cause__ or seen.__context__
    ours = [
        e for e in chain if type(e).__module__.split(".")[0] in ("mlflow", "sqlalchemy", "sqlite3")
    ]
    if not ours:
        return None
    text = " ".join(str(e) for e in ours).lower()
    problem = next((p for words, p in _STORE_PROBLEMS if words in text), None)
    if problem is None:
        return None
    try:
        from prg.tracking import tracking_uri

        store = tracking_uri(cfg.logger.get("tracking_uri"), cfg.paths.root_dir)
    except Exception:  # a config without a logger: the environment's store
        store = os.environ.get("MLFLOW_TRACKING_URI", "the MLflow store")
    return (
        f"MLflow store {store} {problem}: make it writable, or log elsewhere with "
        "logger.tracking_uri=URI or MLFLOW_TRACKING_URI (mlflow=false: no run)"
    )


def compose_config(config_name: str, overrides: list[str], hydra_config: bool = False) -> Any:
    """Compose ``conf/<config_name>.yaml`` with overrides (no Hydra app, no output folder);
    ``hydra_config``: keep the ``hydra`` node."""
    from hydra import compose, initialize_config_dir

    with initialize_config_dir(config_dir=str(config_dir()), version_base="1.3"):
        return compose(
            config_name=config_name, overrides=overrides, return_hydra_config=hydra_config
        )


def route_library_logs() -> None:
    """Send the libraries' info banners and warnings to the run's log (Hydra's console handler on
    stdout and its log file) instead of their own stderr handlers, so that stderr holds only
    what the user must see: a failed command's one error line.

    Lightning attaches its own stream handlers when it is imported before logging is configured
    (it is, by our imports); MLflow does so at its import unless told not to.
    """
    os.environ.setdefault("MLFLOW_CONFIGURE_LOGGING", "false")
    logging.getLogger("alembic").setLevel(logging.WARNING)  # MLflow's schema set-up, per run
    for name in ("lightning", "lightning.pytorch", "lightning.fabric", "mlflow"):
        library = logging.getLogger(name)
        for handler in list(library.handlers):
            if isinstance(handler, logging.StreamHandler) and not isinstance(
                handler, logging.FileHandler
            ):
                library.removeHandler(handler)
        library.propagate = True


@contextmanager
def handle_signals(command: str) -> Iterator[None]:
    """Turn SIGINT, SIGTERM and SIGHUP inside the block into one line and exit code 128 + signal.

    Only in the main thread (Python delivers signals there); see :mod:`prg.signals`. A reader
    of the standard output that goes away (``prg-evaluate --help | head -1``) ends the command
    as SIGPIPE ends a shell tool: quietly, exit code 128 + 13.
    """
    with raising_signals():
        try:
            yield
        except Interrupted as err:
            stop_children()
            fail(
                command,
                f"stopped by {err}; the outputs of earlier runs are left as they were",
                128 + err.signum,
            )
        except BrokenPipeError:
            # the interpreter flushes stdout again at exit: point it at /dev/null first
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            raise SystemExit(128 + signal.SIGPIPE) from None


def end_process(code: int) -> NoReturn:
    """End this process with ``code`` as a normal exit would (``atexit`` handlers run, logging
    and standard streams are flushed) but without the interpreter's teardown, which frees every
    object of torch and the other modules one by one (about 0.35 s after a word is written).
    Threads still running are not waited for: the caller's work must be done."""
    import atexit

    atexit._run_exitfuncs()
    logging.shutdown()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(code)


def _own_process(command: str) -> bool:
    """Whether this process is the console script ``command`` itself (not, e.g., a test calling
    its ``main``), so ending it ends nothing else."""
    main_file = getattr(sys.modules.get("__main__"), "__file__", None) or ""
    return Path(main_file).name == command


def _exit_code(stop: SystemExit) -> int:
    """The process exit code ``sys.exit(stop.code)`` gives (a message: printed, code 1)."""
    if stop.code is None or isinstance(stop.code, int):
        return stop.code or 0
    print(stop.code, file=sys.stderr)
    return 1


def _resolve(task: Callable[[Any], Any] | str) -> Callable[[Any], Any]:
    if callable(task):
        return task
    import importlib

    module, _, function = task.partition(":")
    return getattr(importlib.import_module(module), function)


def hydra_command(
    task: Callable[[Any], Any] | str, config_name: str, command: str, fast_exit: bool = False
) -> Callable[[], None]:
    """Build a console-script ``main`` that runs ``task(cfg)`` under ``@hydra.main``; ``task``
    may be named ``"module:function"``, imported when the task starts (:mod:`prg.commands.entry`).

    ``fast_exit``: a command whose answer is awaited (``prg-write``) ends its own process
    through :func:`end_process` when it is done, successfully or not."""
    import hydra

    @hydra.main(config_path=str(config_dir()), config_name=config_name, version_base="1.3")
    def _run(cfg) -> dict[str, float] | None:
        """The task's metrics (``result.metrics`` when it has them): a multirun job's return
        value, which a search sweeper (``hparams_search=``) optimises."""
        let_go()  # the config is composed: a signal held meanwhile stops the task now
        run_task = _resolve(task)  # before routing: libraries add their log handlers on import
        route_library_logs()
        logging.captureWarnings(True)  # library warnings to the log too
        try:
            return getattr(run_task(cfg), "metrics", None)
        except PRGError as err:
            fail(command, str(err), err.exit_code)
        except OSError as err:
            message = os_error_message(err) or store_error_message(err, cfg)
            if message is None:
                raise
            fail(command, message, 1)
        except Exception as err:  # a store that refuses writes is the machine's, not a bug
            message = store_error_message(err, cfg)
            if message is None:
                raise
            fail(command, message, 1)
        finally:
            logging.captureWarnings(False)

    held = [False]

    def let_go() -> None:
        if held[0]:
            held[0] = False
            release()

    def main() -> None:
        try:
            run_main()
        except SystemExit as stop:
            if not (fast_exit and _own_process(command)):
                raise
            end_process(_exit_code(stop))
        if fast_exit and _own_process(command):
            end_process(0)

    def run_main() -> None:
        with handle_signals(command):
            # Signals wait while Hydra composes the config (until the task starts): OmegaConf's
            # cleanup code can replace an exception raised inside it with one of its own (an
            # empty composition error, exit code 2, instead of "stopped by SIGTERM").
            hold()
            held[0] = True
            try:
                from prg.commands.preflight import preflight  # it imports this module

                preflight(command, config_name, sys.argv[1:])
                if {"-m", "--multirun"} & set(sys.argv[1:]):
                    let_go()  # the jobs may run elsewhere (a launcher): the sweep stays stoppable
                _run()
            finally:
                let_go()

    return main


__all__ = [
    "Interrupted",
    "PRGError",
    "UsageError",
    "check_output",
    "compose_config",
    "config_dir",
    "describe_root",
    "fail",
    "handle_signals",
    "hydra_command",
    "os_error_message",
    "project_root",
    "route_library_logs",
]
