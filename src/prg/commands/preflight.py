"""The command line checked before a command's task runs: one line and exit code 2 for what
Hydra would answer with a traceback or its usage text.

:func:`preflight` composes the command line once against ``conf/`` (each value of a sweep with
the other overrides) and refuses, naming the input and what is accepted: an override the
grammar cannot read, unknown keys (all of them, with the keys accepted where the first was
given; Hydra stops at the first and advises ``+key=``, which would add a key nothing reads), an
unknown config-group option, an interpolation that cannot be resolved, a number out of its
range or an unknown choice (:func:`prg.checks.check_values`), a Hydra log folder that cannot be
created, and Hydra's own flags misused.
"""

from __future__ import annotations

import re
from typing import Any

from omegaconf import OmegaConf

from prg.checks import check_values, unknown_key
from prg.commands.cli import check_output, compose_config, fail
from prg.errors import UsageError


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


def _unresolvable(cfg: Any, overrides: list[str]) -> str | None:
    """One line for the first interpolation of ``cfg`` that cannot be resolved (``${oc.env:NOPE}``,
    ``${no.such.key}``), None if all resolve. The keys the user set are tried first, so the line
    names the option given rather than another that interpolates it."""
    from omegaconf.errors import OmegaConfBaseException

    given = [_key_of(o) for o in overrides if "=" in o]
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


def preflight(command: str, config_name: str, argv: list[str]) -> None:
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
    """The checks of :func:`preflight` on one list of plain overrides (``log_dir``: also the
    Hydra log folder of a single run)."""
    overrides = [
        a
        for a in argv
        if a.startswith("hydra.run.dir=") or not a.lstrip("+~").startswith(("hydra.", "hydra/"))
    ]
    try:
        cfg = compose_config(config_name, overrides, hydra_config=True)
    except Exception as err:  # Hydra raises several types; all mean a bad override
        fail(command, composition_error(err, config_name, overrides), 2)
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
        fail(command, composition_error(err, "", overrides), 2)
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


def composition_error(err: Exception, config_name: str, overrides: list[str]) -> str:
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
    rest = list(overrides)
    failure: Exception | None = err
    while failure is not None:
        key = _unknown_override(failure)
        kept = [o for o in rest if _key_of(o) != key]
        if key is None or len(kept) == len(rest):
            break  # not an unknown key, or one no override names as such: Hydra's message
        unknown.append(key)
        rest = kept
        try:
            known = OmegaConf.to_container(compose_config(config_name, rest))
            failure = None
        except Exception as again:  # Hydra raises several types
            failure = again
    if unknown:
        if failure is not None:  # the rest fails for another reason too
            return f"{composition_error(failure, config_name, rest)} (also unknown: {', '.join(unknown)})"
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
