"""The ``prg-study`` program: its parser, the ``build`` sub-command, and how a command runs.

:func:`main` builds the parser with ``build`` and the sub-commands that its ``registrars`` add
(``register(subparsers)``: the entry point :mod:`studies.cli` adds ``analyze``, ``power`` and
``simulate`` from :mod:`studies.analysis.commands`), runs the chosen command and turns its
errors into exit codes: a mistake the user can fix (:class:`prg.errors.UsageError`) is one line,
``prg-study: error: <message>``, exit code 2; other :class:`prg.errors.PRGError` and an
:class:`OSError` about a file or the disk (see :func:`prg.commands.cli.os_error_message`) exit 1;
a signal 128 + its number (:func:`prg.commands.cli.handle_signals`).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import NoReturn

from prg.commands.cli import check_output, handle_signals, os_error_message
from prg.errors import PRGError, UsageError

PROG = "prg-study"


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line: ``prg-study: error: <message>`` (exit 2)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{PROG}: error: {' '.join(message.split())}\n")


#: Where a pilot build looks for held-out writers' letters (relative to the working directory).
DEFAULT_PILOT_DATA = Path("data") / "prepared" / "synthetic"


def _say(line: str) -> None:
    print(f"{PROG}: {line}", file=sys.stderr, flush=True)


def build_command(args: argparse.Namespace) -> int:
    """``prg-study build``: see :func:`studies.bundle.build_study`."""
    from studies.bundle import build_study, default_out
    from studies.design_config import load_study

    config = load_study(args.config, args.set or [])
    pilot_data = args.pilot_data
    if pilot_data is not None and not (Path(pilot_data) / "test.npz").is_file():
        raise UsageError(
            f"--pilot-data {pilot_data}: no test.npz there; give a folder prg-prepare made, "
            f"e.g. {DEFAULT_PILOT_DATA}"
        )
    out = check_output(args.out or default_out(config.name, args.pilot), "--out")
    report = build_study(
        config,
        human_dirs=args.human or [],
        robot_dir=args.robot,
        ckpt=args.ckpt,
        out_dir=out,
        progress=None if args.quiet else _say,
        pilot=args.pilot,
        pilot_data=pilot_data if pilot_data is not None else DEFAULT_PILOT_DATA,
    )
    for note in report.notes:
        _say(f"note: {note}")
    if report.pilot:
        made = (
            f"{report.stand_ins} stand-ins for the missing human samples"
            if report.stand_ins
            else "the human samples"
        )
        _say(
            f"{config.name}: PILOT build — {report.out_dir}/index.html runs with {made}; try "
            "the pages, do not collect data with it (answers marked pilot, never POSTed)"
        )
        for line in report.missing:
            _say(f"stand-ins for: {line}")
        return 0
    if report.ready:
        _say(
            f"{config.name}: ready — {report.out_dir}/index.html "
            f"({config.participants} rows, {report.n_stimuli} stimuli, {report.app_version})"
        )
        return 0
    _say(f"{config.name}: NOT READY — built the robot stimuli and {report.out_dir}/capture/")
    for line in report.missing:
        _say(f"missing: {line}")
    _say(
        f"to try the pages now: prg-study build {args.config} --pilot "
        f"(a PILOT copy with stand-ins, in {default_out(config.name, pilot=True)}/ by default)"
    )
    if args.require_ready:
        raise UsageError(f"{config.name} is not ready: {len(report.missing)} missing item(s)")
    return 0


def _add_build(subparsers) -> None:
    p = subparsers.add_parser(
        "build",
        help="build a study's static web folder (stimuli, trial list, pages)",
        description=(
            "Build studies/<name>/build/: the questionnaire (index.html), the capture page for "
            "human writers (capture/), the stimuli and the counterbalanced trial list."
        ),
    )
    p.add_argument("config", help="the study YAML, e.g. conf/study/turing.yaml")
    p.add_argument(
        "--human",
        action="append",
        metavar="DIR",
        help="folder of human samples (capture JSON, strokes JSON, SVG); repeatable",
    )
    p.add_argument(
        "--robot",
        metavar="DIR",
        help="ready robot word trajectories (<word>.json or <word>/word.json) instead of "
        "writing the words with the model",
    )
    p.add_argument("--ckpt", metavar="PATH", help="model checkpoint for the robot's words")
    p.add_argument(
        "--out",
        metavar="DIR",
        help="output folder (default studies/<name>/build, with --pilot studies/<name>/pilot)",
    )
    p.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="override a study setting, e.g. --set participants=40 --set completion.code=XYZ",
    )
    p.add_argument(
        "--require-ready",
        action="store_true",
        help="exit 2 when human samples are missing (default: build what can be built)",
    )
    p.add_argument(
        "--pilot",
        action="store_true",
        help="a pilot copy (default folder studies/<name>/pilot): missing human samples are "
        "filled with held-out writers' words from --pilot-data (else stand-ins made from the "
        "robot's), to try the pages before the human writers have written; every page says "
        "PILOT, answers are marked pilot, never POSTed",
    )
    p.add_argument(
        "--pilot-data",
        metavar="DIR",
        help="prepared dataset whose held-out writers write a pilot's human words (default "
        f"{DEFAULT_PILOT_DATA} when it exists, else stand-ins made from the robot's words)",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=build_command)


def judge_command(args: argparse.Namespace) -> int:
    """``prg-study judge``: see :func:`studies.judge.judge`."""
    from studies.judge import judge, summary_lines

    if args.options < 2:
        raise UsageError(f"--options {args.options}: give 2 or more (the robot and the humans)")
    if args.robot_words < 0:
        raise UsageError(f"--robot-words {args.robot_words}: give 0 or more")
    result = judge(
        args.folder, n_options=args.options, seed=args.seed, robot_per_word=args.robot_words
    )
    for line in summary_lines(result):
        _say(line)
    _say(f"wrote {Path(args.folder) / 'judge.json'}")
    return 0


def _add_judge(subparsers) -> None:
    p = subparsers.add_parser(
        "judge",
        help="score a built study's stimuli before any participant: a classifier two-sample "
        "test and a simulated observer",
        description=(
            "Does a built study give the robot away? A classifier two-sample test (robot words "
            "against the study's human words, on trajectories and on the rendered images) and "
            "a simulated observer for the Turing question; writes judge.json in the folder."
        ),
    )
    p.add_argument("folder", help="a built study, e.g. studies/turing/pilot")
    p.add_argument("--options", type=int, default=5, help="samples per trial (default 5)")
    p.add_argument("--seed", type=int, default=0, help="seed of the simulated trials")
    p.add_argument(
        "--robot-words",
        type=int,
        default=0,
        metavar="N",
        help="write N more robot words a word, in other hands, as the study's robot writes "
        "(the study shows one; more give the judge something to learn from)",
    )
    p.set_defaults(func=judge_command)


Registrar = Callable[[argparse._SubParsersAction], None]  #: adds sub-commands to a parser


def make_parser(*registrars: Registrar) -> Parser:
    """The ``prg-study`` parser: ``build``, then the sub-commands each of ``registrars`` adds."""
    parser = Parser(
        prog=PROG,
        description="Build and analyse human-vs-robot handwriting user studies.",
        epilog="Run 'prg-study COMMAND --help' for a command's options.",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    _add_build(subparsers)
    _add_judge(subparsers)
    for register in registrars:
        register(subparsers)
    return parser


def main(registrars: Sequence[Registrar], argv: Sequence[str] | None = None) -> int:
    """Run ``prg-study`` with the sub-commands of ``registrars``; returns the exit code."""
    with handle_signals(PROG):
        return _main(make_parser(*registrars), argv)


def _main(parser: Parser, argv: Sequence[str] | None) -> int:
    args = parser.parse_args(argv)
    if getattr(args, "func", None) is None:
        parser.error("choose a command: " + ", ".join(_choices(parser)))
    try:
        return int(args.func(args) or 0)
    except PRGError as err:
        print(f"{PROG}: error: {' '.join(str(err).split())}", file=sys.stderr)
        return err.exit_code
    except OSError as err:
        message = os_error_message(err)
        if message is None:
            raise
        print(f"{PROG}: error: {message}", file=sys.stderr)
        return 1


def _choices(parser: argparse.ArgumentParser) -> list[str]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return list(action.choices)
    return []
