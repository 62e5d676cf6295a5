"""Thin Hydra entry points with one-line errors.

Every ``prg-*`` command is ``hydra_command(task, config_name, command)``. Before Hydra runs, the
command line is composed once against ``conf/`` so that an unknown config group, a typo in a key
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
import re
import signal
import sys
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, NoReturn

import tomllib
from omegaconf import OmegaConf

from prg.checks import check_values, unknown_key
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


def _hydra_flags_error(argv: list[str]) -> str | None:
    """What Hydra's own argument parser would refuse in ``argv`` (it prints its usage, 8 lines,
    and exits); None when it accepts it."""
    from hydra._internal.utils import get_args_parser

    parser = get_args_parser()

    def refuse(message: str):
        raise UsageError(message)

    parser.error = refuse  # argparse's default prints the usage and exits
    try:
        args, unknown = parser.parse_known_args(argv)
    except UsageError as err:
        return str(err)
    if unknown:
        return f"unknown option {unknown[0]}"
    modes = {"--run": args.run, "--multirun": args.multirun, "--cfg": args.cfg is not None}
    modes |= {"--info": args.info is not None, "--shell-completion": args.shell_completion}
    given = [flag for flag, on in modes.items() if on]
    if len(given) > 1:  # Hydra raises a ValueError with its traceback
        return f"{' and '.join(given)} cannot be combined: give one of {', '.join(modes)}"
    return None


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


def _unresolvable(cfg: Any, overrides: list[str]) -> str | None:
    """One line for the first interpolation of ``cfg`` that cannot be resolved (``${oc.env:NOPE}``,
    ``${no.such.key}``), None if all resolve. The keys the user set are tried first, so the line
    names the option given rather than another that interpolates it."""
    from omegaconf import OmegaConf
    from omegaconf.errors import OmegaConfBaseException

    given = [o.partition("=")[0].lstrip("+~") for o in overrides if "=" in o]
    rest = [k for k in cfg if k != "hydra"]
    for key in [*given, *rest, "hydra.run.dir"]:
        try:
            node = OmegaConf.select(cfg, key, throw_on_missing=False)
            if OmegaConf.is_config(node):
                OmegaConf.to_container(node, resolve=True)
        except OmegaConfBaseException as err:
            where = err.full_key or key
            reason = str(getattr(err, "msg", err)).splitlines()[0]
            reason = reason.replace("KeyError raised while resolving interpolation: ", "")
            value = OmegaConf.to_container(cfg, resolve=False)
            for part in where.split("."):
                value = value.get(part) if isinstance(value, dict) else None
            shown = f"={value}" if isinstance(value, str) else ""
            return f"{where}{shown} cannot be resolved: {reason}"
    return None


def _preflight(command: str, config_name: str, argv: list[str]) -> None:
    """Compose the command line once; report a bad override as one line (exit 2): an unknown
    key or config-group option (naming the accepted ones), an unresolvable interpolation, a
    number out of its range or an unknown choice (:func:`prg.checks.check_values`).

    Also refuses a Hydra log folder (``hydra.run.dir``, under ``paths.log_dir``) that cannot be
    created, which Hydra itself would report with a traceback. With Hydra's own flags, an
    unknown flag or a bad flag value is refused in one line instead of Hydra's usage text, and
    the overrides of ``--cfg`` and ``-m`` are checked as above (a sweep's every value, each
    with the other overrides, :func:`_sweep_variants`); flags that change what is composed
    (``--config-name``, ``--config-dir`` ...) or print help leave the overrides to Hydra.
    """
    if any(arg.startswith("-") for arg in argv):
        message = _hydra_flags_error(argv)
        if message:
            fail(command, f"{message} (the options are Hydra's: {command} --help)", 2)
        overrides = _flagged_overrides(argv)
        if overrides is not None:
            for variant in _sweep_variants(command, overrides):
                _check_composition(command, config_name, variant, log_dir=False)
        return
    _check_composition(command, config_name, argv, log_dir=True)


def _check_composition(command: str, config_name: str, argv: list[str], *, log_dir: bool) -> None:
    """The checks of :func:`_preflight` on one list of plain overrides (``log_dir``: also the
    Hydra log folder of a single run)."""
    overrides = [
        a
        for a in argv
        if a.startswith("hydra.run.dir=") or not a.lstrip("+~").startswith(("hydra.", "hydra/"))
    ]
    try:
        cfg = compose_config(config_name, overrides, hydra_config=True)
    except Exception as err:  # Hydra raises several types; all mean a bad override
        fail(command, _composition_error(err, config_name, overrides), 2)
    unresolved = _unresolvable(cfg, overrides)
    if unresolved:
        fail(command, unresolved, 2)
    try:
        check_values(OmegaConf.masked_copy(cfg, [key for key in cfg if key != "hydra"]))
        if log_dir:
            check_output(cfg.hydra.run.dir, "Hydra's log folder (paths.log_dir)")
    except UsageError as err:
        fail(command, str(err), 2)


# Hydra flags after which the overrides are not composed against conf/<command>.yaml as given
_OTHER_COMPOSITION = (
    "help",
    "hydra_help",
    "info",
    "shell_completion",
    "config_path",
    "config_name",
    "config_dir",
    "experimental_rerun",
)
_MAX_VARIANTS = 64  # compositions checked for one sweep (each ~0.1 s)


def _flagged_overrides(argv: list[str]) -> list[str] | None:
    """The overrides of a command line with Hydra flags, None when the flags leave them to Hydra
    (help, another config, shell completion ...)."""
    from hydra._internal.utils import get_args_parser

    args, _ = get_args_parser().parse_known_args(argv)
    if any(getattr(args, flag, None) for flag in _OTHER_COMPOSITION):
        return None
    return list(args.overrides)


def _sweep_variants(command: str, overrides: list[str]) -> list[list[str]]:
    """Plain override lists that together use every value of every sweep (``seed=0,1``,
    ``choice(...)``, ``range(...)``): each sweep's value with the first value of the others. A
    malformed override is refused in one line here; sweeps that cannot be listed
    (``interval(...)``, ``glob(...)``) are left to the sweeper."""
    from hydra.core.override_parser.overrides_parser import OverridesParser
    from hydra.errors import HydraException

    try:
        parsed = OverridesParser.create().parse_overrides(overrides)
    except HydraException as err:
        fail(command, _composition_error(err, "", overrides), 2)
    plain: list[str] = []
    sweeps: list[tuple[str, list[str]]] = []
    for override in parsed:
        if not override.is_sweep_override():
            plain.append(override.input_line or "")
            continue
        try:
            values = list(override.sweep_string_iterator())
        except HydraException:
            continue
        if values:
            sweeps.append((override.get_key_element(), values))
    first = [f"{key}={values[0]}" for key, values in sweeps]
    variants = [plain + first]
    for i, (key, values) in enumerate(sweeps):
        for value in values[1:]:
            if len(variants) >= _MAX_VARIANTS:
                return variants
            variants.append(plain + first[:i] + [f"{key}={value}"] + first[i + 1 :])
    return variants


# Hydra's message for an unknown option of a config group (``model=musee``), whitespace joined
_MISSING_OPTION = re.compile(
    r"Could not find '(.+)/([^/']+)' Available options in '[^']*': (.*?)(?: Config search path|$)"
)
# Hydra's message for a config group the command does not have (``prg-write model=muse``)
_NOT_A_GROUP = re.compile(r"^Could not override '([^']+)'\. No match in the defaults list")


def _unknown_override(err: Exception) -> str | None:
    """The key of an override that names nothing in the config, when that is why Hydra failed."""
    from omegaconf.errors import OmegaConfBaseException

    message = " ".join(str(err).split())
    group = _NOT_A_GROUP.match(message)
    if group:
        return group.group(1)
    cause = err.__cause__
    if message.startswith("Could not override") and isinstance(cause, OmegaConfBaseException):
        return cause.full_key or None
    return None


def _unreadable_override(overrides: list[str]) -> str | None:
    """The line for the first override Hydra's grammar cannot read, naming it and why (Hydra's
    message for a whole command line names neither)."""
    from hydra.core.override_parser.overrides_parser import OverridesParser
    from hydra.errors import HydraException

    parser = OverridesParser.create()
    for override in overrides:
        try:
            parser.parse_override(override)
        except HydraException as err:
            reason = " ".join(str(err).split())
            cut = reason.find(" expecting {")  # the grammar's whole list of tokens
            reason = reason[:cut] if cut > 0 else reason
            return (
                f"cannot read {override}: {reason}; a value with spaces, commas or symbols needs"
                """ quotes: 'key="..."'"""
            )
    return None


def _key_of(override: str) -> str:
    return override.lstrip("+~").partition("=")[0]


def _composition_error(err: Exception, config_name: str, overrides: list[str]) -> str:
    """One line for a command line that does not compose: the unknown keys (with the accepted
    ones), an unknown option of a config group (with the options), or Hydra's own message."""
    unreadable = _unreadable_override(overrides)
    if unreadable:
        return unreadable
    message = " ".join(str(err).split())
    # Hydra stops at the first unknown key (advising +key=, which would add an unused one): drop
    # each unknown key in turn until the rest composes, so that the line names them all and
    # lists what is accepted where the first was given
    unknown: list[str] = []
    failure: Exception | None = err
    while failure is not None and len(unknown) < len(overrides):
        key = _unknown_override(failure)
        if key is None:
            break
        unknown.append(key)
        rest = [o for o in overrides if _key_of(o) not in unknown]
        try:
            known = OmegaConf.to_container(compose_config(config_name, rest))
            failure = None
        except Exception as again:  # Hydra raises several types
            failure = again
    if unknown:
        if failure is not None:  # the rest fails for another reason too
            return f"{_composition_error(failure, config_name, rest)} (also unknown: {', '.join(unknown)})"
        line = unknown_key(unknown[0], known)
        if len(unknown) > 1:
            line += f" (also unknown: {', '.join(unknown[1:])})"
        variables = [k for k in unknown if k.isupper()]
        if variables:
            line += (
                f"; {variables[0]} looks like an environment variable: put it before the command"
            )
        return line
    group = _MISSING_OPTION.search(message)
    if group:
        options = [o for o in group.group(3).split() if not o.startswith("_")]  # _base_ files
        return f"unknown {group.group(1)} {group.group(2)}; accepted: {', '.join(options)}"
    cut = message.find("Set the environment variable HYDRA_FULL_ERROR")
    message = (message[:cut] if cut > 0 else message).strip()
    cut = message.find(" See https://hydra.cc/docs/")  # the grammar's page, after the reason
    message = message[:cut] if cut > 0 else message
    return message


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
                _preflight(command, config_name, sys.argv[1:])
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
