"""``prg-study analyze | power | simulate``: the analysis sub-commands of the ``prg-study`` entry point.

The entry point (``studies/cli.py``) calls :func:`register` on its sub-parsers and then
``args.func(args)``; every handler returns an exit code and raises
:class:`prg.errors.UsageError` for bad input (the entry point prints it as one line, exit 2).
``python -m studies.analysis.commands ...`` is ``prg-study ...`` (:func:`studies.program.main`
with :func:`register`).

Usage::

    prg-study analyze RESPONSES.csv [--study conf/study/turing.yaml] [--out DIR] [--truth JSON]
                      [--margin M] [--alpha A] [--chance C] [--margin-source preregistered|data]
                      [--kind turing|readability] [--include-attention-rows] [--keep-inattentive] [--no-mixed]
    prg-study power turing [--margin 0.05] [--rate 0.2 0.22] [--power 0.8 0.9] [--words 10 20]
                           [--icc 0.1] [--word-icc 0.005] [--trials 500] [--out plan.csv]
    prg-study power readability [--margin 0.1] [--rate 0.8] [--difference 0 0.05] [--power 0.8 0.9]
                                [--words 10] [--icc 0.1] [--participants 30] [--out plan.csv]
    prg-study simulate turing|readability --participants N --true-rate R [--human-rate R]
                       [--icc 0.1] [--word-icc 0] [--seed S] --out responses.csv
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from prg.commands.cli import check_output
from prg.errors import UsageError
from prg.files import atomic_path

KINDS = ("turing", "readability")
MAX_SIMULATED_ROWS = 1_000_000  #: about 20 s and 100 MB of CSV
MAX_SIMULATED_WORDS = 1_000


def _checked(parse, what: str, ok, outside: str):
    """An argparse ``type``: ``parse`` the text (else "is not {what}"), then check it with ``ok``
    (else "{value} {outside}"; NaN and infinities fail every range below)."""

    def check(value: str):
        try:
            x = parse(value)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{value!r} is not {what}") from None
        if not ok(x):
            raise argparse.ArgumentTypeError(f"{value} {outside}")
        return x

    return check


_rate = _checked(float, "a number", lambda x: 0 < x < 1, "is outside (0, 1)")
_difference = _checked(
    float, "a number", lambda x: -1 < x < 1, "is outside (-1, 1) (a difference of rates)"
)
_share = _checked(
    float,
    "a number",
    lambda x: 0 <= x <= 0.5,
    "is outside 0-0.5 (a share of the answers' variance)",
)
_positive_int = _checked(int, "a whole number", lambda x: x >= 1, "must be at least 1")
_count = _checked(int, "a whole number", lambda x: x >= 0, "must be 0 or more")


def _confidence(value: str) -> float:
    x = float(value) if value.replace(".", "", 1).isdigit() else math.nan
    if not 1 < x < 5:
        raise argparse.ArgumentTypeError(f"{value} is outside (1, 5)")
    return x


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``analyze``, ``power`` and ``simulate`` sub-commands to ``subparsers``."""
    _add_analyze(subparsers)
    _add_power(subparsers)
    _add_simulate(subparsers)


def _add_variance_shares(parser: argparse.ArgumentParser, icc: str, word_icc: str, **default):
    """``--icc`` and ``--word-icc``: the participant and word shares of the answers' variance
    (``icc``, ``word_icc``: the defaults as the help states them)."""
    parser.add_argument(
        "--icc",
        type=_share,
        help=f"participant share of the answers' variance (default {icc})",
        **default,
    )
    parser.add_argument(
        "--word-icc",
        type=_share,
        help=f"word share of the answers' variance (default {word_icc})",
        **default,
    )


def _command(
    subparsers: argparse._SubParsersAction, name: str, run: Callable[..., Any], **texts: str
) -> argparse.ArgumentParser:
    """The sub-command ``name`` (``help``, ``description`` in ``texts``), which runs ``run``."""
    parser = subparsers.add_parser(name, **texts)
    parser.set_defaults(func=run)
    return parser


def _add_analyze(subparsers: argparse._SubParsersAction) -> None:
    a = _command(
        subparsers,
        "analyze",
        run_analyze,
        help="analyse a long-format responses CSV; write the report",
        description="Check and analyse a responses CSV; write report.md/.html, tidy CSVs and figures.",
    )
    a.add_argument("responses", help="long-format responses CSV (one row per trial)")
    a.add_argument(
        "--study", metavar="YAML", help="study config (conf/study/turing.yaml or readability.yaml)"
    )
    a.add_argument(
        "--out", metavar="DIR", help="report folder (default: reports/study/<responses name>)"
    )
    a.add_argument(
        "--kind",
        choices=KINDS,
        help="analyse only this study's rows (default: the study column / config)",
    )
    a.add_argument(
        "--margin", type=_rate, help="equivalence / non-inferiority margin (overrides the config)"
    )
    a.add_argument(
        "--margin-source", choices=("preregistered", "data"), help="where the margin came from"
    )
    a.add_argument("--alpha", type=_rate, help="significance level (default 0.05)")
    a.add_argument("--chance", type=_rate, help="chance rate of picking the robot (default 1/5)")
    a.add_argument(
        "--include-attention-rows", action="store_true", help="analyse attention-check rows too"
    )
    a.add_argument(
        "--keep-inattentive",
        action="store_true",
        help="keep participants who failed an attention check",
    )
    a.add_argument(
        "--truth",
        action="append",
        metavar="JSON",
        help="simulated responses: the simulation's truth, shown beside each estimate; one per "
        "study (default: <responses name>.truth.json beside them, as prg-study simulate "
        "writes it)",
    )
    a.add_argument(
        "--judge",
        metavar="JSON",
        help="a built study's judge.json (prg-study judge) to report beside the analysis",
    )
    a.add_argument("--no-mixed", action="store_true", help="skip the crossed mixed logit (faster)")
    a.add_argument("--no-paper", action="store_true", help="leave out the paper-reproduction table")


def _add_power(subparsers: argparse._SubParsersAction) -> None:
    p = _command(
        subparsers,
        "power",
        run_power,
        help="sample-size planner for either study",
        description="Power and sample size for the Turing-like test (equivalence to chance) or the "
        "readability study (paired TOST / non-inferiority).",
    )
    p.add_argument("kind", choices=KINDS)
    p.add_argument(
        "--margin", type=_rate, help="equivalence margin (default 0.05 turing, 0.10 readability)"
    )
    p.add_argument(
        "--rate",
        type=_rate,
        nargs="+",
        help="true rate(s): turing P(pick robot) (default 0.20 0.22); readability human success (default 0.80)",
    )
    p.add_argument(
        "--difference",
        type=_difference,
        nargs="+",
        help="readability: true robot minus human (default 0 0.05)",
    )
    p.add_argument(
        "--power",
        type=_rate,
        nargs="+",
        default=[0.8, 0.9],
        help="target power(s) (default 0.8 0.9)",
    )
    p.add_argument(
        "--words",
        type=_positive_int,
        nargs="+",
        help="words per participant (default 10 20 turing, 10 readability)",
    )
    _add_variance_shares(p, "0.10", "0.005")
    p.add_argument("--alpha", type=_rate, default=0.05)
    p.add_argument("--chance", type=_rate, default=0.2, help="turing: chance rate (default 0.2)")
    p.add_argument(
        "--trials",
        type=_positive_int,
        nargs="+",
        help="turing: also print power at these numbers of trials (default 500)",
    )
    p.add_argument(
        "--participants",
        type=_positive_int,
        nargs="+",
        help="readability: also print power at these sizes (default 30)",
    )
    p.add_argument("--out", metavar="CSV", help="write the plan as a CSV too")


def _add_simulate(subparsers: argparse._SubParsersAction) -> None:
    s = _command(
        subparsers,
        "simulate",
        run_simulate,
        help="simulated participants with known truth, as a responses CSV",
        description="Draw simulated participants from a crossed logit model with known truth; write "
        "a responses CSV in the exact schema and the truth as JSON next to it.",
    )
    s.add_argument("kind", choices=KINDS)
    s.add_argument("--participants", type=_positive_int, required=True)
    s.add_argument(
        "--true-rate",
        type=_rate,
        required=True,
        help="turing: population P(pick the robot); readability: the robot's success rate",
    )
    s.add_argument(
        "--human-rate",
        type=_rate,
        help="readability: the human's success rate (default: = --true-rate)",
    )
    _add_variance_shares(s, "0", "0", default=0.0)
    s.add_argument(
        "--words", help="comma-separated words, or a number of words (default: 10 words)"
    )
    s.add_argument("--study", metavar="YAML", help="study config to take the words from")
    s.add_argument(
        "--confidence-mean",
        type=_confidence,
        default=3.0,
        help="turing: population mean confidence (default 3)",
    )
    s.add_argument(
        "--confidence-icc",
        type=_share,
        default=0.1,
        help="turing: participant share of confidence (default 0.1)",
    )
    s.add_argument(
        "--attention-checks",
        type=_count,
        default=1,
        help="attention-check trials per participant (default 1)",
    )
    s.add_argument(
        "--inattentive",
        type=_count,
        default=0,
        help="extra participants who answer at random and fail the checks",
    )
    s.add_argument("--seed", type=_count, default=0)
    s.add_argument(
        "--out",
        required=True,
        metavar="CSV",
        help="responses CSV to write (truth: <name>.truth.json)",
    )


def run_analyze(args: argparse.Namespace) -> int:
    """``prg-study analyze``: check, analyse, write the report folder; print where it went."""
    from studies.analysis.analyze import analyze_file
    from studies.analysis.config import load_config, with_overrides
    from studies.analysis.report import check_out_dir, write_report
    from studies.analysis.truth import read_truth, truth_path_for, with_truth

    cfg = load_config(args.study)
    cfg = with_overrides(
        cfg,
        kind=args.kind,
        margin=args.margin,
        margin_source=args.margin_source,
        alpha=args.alpha,
        chance=args.chance,
        include_attention_rows=True if args.include_attention_rows else None,
        exclude_failed_attention=False if args.keep_inattentive else None,
        mixed_model=False if args.no_mixed else None,
    )
    out = check_out_dir(args.out or Path("reports") / "study" / Path(args.responses).stem)
    check_output(out, "--out")
    truths = [(read_truth(path), path) for path in args.truth or []]  # bad files fail first
    judge = read_judge(args.judge) if args.judge else None
    analysis = analyze_file(args.responses, cfg)
    beside = truth_path_for(args.responses)
    if not truths and analysis.origin == "simulated" and beside.is_file():
        truths = [(read_truth(beside, "the truth file"), str(beside))]
    analysis = with_truth(analysis, truths)
    write_report(analysis, out, paper=not args.no_paper, judge=judge)
    if analysis.origin != "study":
        known = [f"; {st.kind} truth: {st.truth_path}" for st in analysis.studies if st.truth]
        print(f"data: {analysis.origin.upper()} (the report says so first{''.join(known)})")
    for st in analysis.studies:
        for line in st.conclusions:
            print(f"{st.kind}: {line.replace('**', '')}")
        for w in st.warnings:
            print(f"{st.kind}: warning: {w}")
    print(f"report: {out / 'report.html'}")
    return 0


def read_judge(path: str) -> dict:
    """A ``judge.json`` written by ``prg-study judge``, or one line naming the file."""
    from prg.files import read_json

    doc = read_json(path, "--judge file")
    if not isinstance(doc, dict) or not {"observer", "c2st", "words"} <= set(doc):
        raise UsageError(f"--judge {path}: not a judge.json written by prg-study judge")
    return doc


def _print_table(frame, columns: list[str]) -> None:
    import pandas as pd

    view = frame[columns].copy()
    for c in view.columns:
        if pd.api.types.is_float_dtype(view[c]):
            view[c] = view[c].map(
                lambda x: (
                    "–"
                    if x != x
                    else (f"{x:.0f}" if float(x).is_integer() and abs(x) > 1 else f"{x:.3g}")
                )
            )
    print(view.to_string(index=False))


def run_power(args: argparse.Namespace) -> int:
    """``prg-study power``: print (and optionally write) the sample-size table."""
    import pandas as pd

    from studies.analysis import power as P

    if args.out:
        check_output(args.out, "--out", folder=False)
    icc = P.DEFAULT_ICC if args.icc is None else args.icc
    word_icc = P.DEFAULT_WORD_ICC if args.word_icc is None else args.word_icc
    if icc + word_icc > 0.5:
        raise UsageError(f"--icc {icc} plus --word-icc {word_icc} must be at most 0.5")
    if args.kind == "turing":
        margin = 0.05 if args.margin is None else args.margin
        if not (args.chance - margin > 0 and args.chance + margin < 1):
            raise UsageError(f"--chance {args.chance} ± --margin {margin} must stay inside (0, 1)")
        plan = P.turing_plan(
            args.rate or [0.20, 0.22],
            args.power,
            args.chance,
            margin,
            args.alpha,
            args.words or [10, 20],
            icc,
            word_icc,
        )
        at = P.turing_power_at(
            args.trials or [500], args.rate or [0.20, 0.22], args.chance, margin, args.alpha
        )
        print(
            f"Study 1: exact binomial TOST of chance {args.chance:g} ± {margin:g} (alpha {args.alpha:g}); "
            f"participants for icc {icc:g}, word_icc {word_icc:g}"
        )
        _print_table(
            plan,
            [
                "true_rate",
                "target_power",
                "trials",
                "trials_first",
                "words",
                "participants",
                "power_achieved",
            ],
        )
        print()
        _print_table(at, ["trials", "true_rate", "power"])
        unreachable = plan[plan["trials"].isna()]
        if len(unreachable):
            print(
                f"(no sample size: a true rate outside chance ± {margin:g} can never be shown equivalent)"
            )
    else:
        margin = 0.10 if args.margin is None else args.margin
        words = (args.words or [10])[0]
        if words < 2:
            raise UsageError(
                f"--words {words}: readability needs at least 2 words (half per writer)"
            )
        diffs = args.difference if args.difference is not None else [0.0, 0.05]
        rates = args.rate or [0.80]
        for r in rates:
            for d in diffs:
                if not 0 < r + d < 1:
                    raise UsageError(f"--rate {r} plus --difference {d} is outside (0, 1)")
        plan = P.readability_plan(
            rates, diffs, args.power, margin, args.alpha, words, icc, word_icc
        )
        at = pd.concat(
            [
                P.readability_power_at(
                    args.participants or [30], r, d, margin, args.alpha, words, icc, word_icc
                )
                for r in rates
                for d in diffs
            ],
            ignore_index=True,
        )
        print(
            f"Study 2: paired TOST ±{margin:g} and non-inferiority (alpha {args.alpha:g}); "
            f"{words // 2} words per writer, icc {icc:g}, word_icc {word_icc:g}"
        )
        _print_table(
            plan,
            [
                "test",
                "human_rate",
                "robot_rate",
                "target_power",
                "sd_difference",
                "participants",
                "power_achieved",
            ],
        )
        print()
        _print_table(
            at, ["participants", "human_rate", "robot_rate", "power_tost", "power_noninferiority"]
        )
    if args.out:
        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        _write_files(out, lambda path: plan.to_csv(path, index=False))
        print(f"plan: {out}")
    return 0


def _write_files(*pairs) -> None:
    """``path, write(tmp_path), path, write(tmp_path) ...``: every file written under a
    temporary name first, then all renamed; a failure leaves none of them half-written."""
    with contextlib.ExitStack() as stack:
        for path, write in zip(pairs[::2], pairs[1::2], strict=True):
            write(stack.enter_context(atomic_path(path)))


def _words(args: argparse.Namespace) -> list[str]:
    from studies.analysis.config import load_config
    from studies.analysis.participants import DEFAULT_WORDS

    if args.words:
        text = args.words.strip()
        if text.isdigit():
            n = int(text)
            if not 2 <= n <= MAX_SIMULATED_WORDS:
                raise UsageError(f"--words {text}: give 2 to {MAX_SIMULATED_WORDS} words")
            base = list(DEFAULT_WORDS)
            return (
                base[:n]
                if n <= len(base)
                else base + [f"word{i:02d}" for i in range(len(base) + 1, n + 1)]
            )
        words = [w.strip() for w in text.split(",") if w.strip()]
        if not 2 <= len(words) <= MAX_SIMULATED_WORDS or len(set(words)) != len(words):
            raise UsageError(
                f"--words: give 2 to {MAX_SIMULATED_WORDS} different comma-separated words, "
                f"got {len(words)}" + (" (some twice)" if len(set(words)) != len(words) else "")
            )
        return words
    if args.study:
        cfg = load_config(args.study)
        if cfg.words:
            return list(cfg.words)
    return list(DEFAULT_WORDS)


def run_simulate(args: argparse.Namespace) -> int:
    """``prg-study simulate``: write a simulated responses CSV and its truth JSON."""
    from studies.analysis.participants import simulate_readability, simulate_turing

    if args.icc + args.word_icc > 0.5:
        raise UsageError(f"--icc {args.icc} plus --word-icc {args.word_icc} must be at most 0.5")
    out = Path(args.out)
    if out.suffix.lower() != ".csv":
        raise UsageError(f"--out {out}: expected a .csv file name")
    check_output(out, "--out", folder=False)
    check_output(out.with_suffix(".truth.json"), "--out (its truth file)", folder=False)
    words = _words(args)
    rows = (args.participants + args.inattentive) * (len(words) + args.attention_checks)
    if rows > MAX_SIMULATED_ROWS:
        raise UsageError(
            f"--participants {args.participants} (+ --inattentive {args.inattentive}) x "
            f"{len(words)} words (+ --attention-checks {args.attention_checks}) is {rows} rows; "
            f"at most {MAX_SIMULATED_ROWS}"
        )
    common = dict(
        icc=args.icc,
        word_icc=args.word_icc,
        words=words,
        attention_checks=args.attention_checks,
        inattentive=args.inattentive,
        seed=args.seed,
    )
    if args.kind == "turing":
        if args.human_rate is not None:
            raise UsageError(
                "--human-rate is for the readability study; turing takes --true-rate only"
            )
        frame, truth = simulate_turing(
            args.participants,
            args.true_rate,
            confidence_mean=args.confidence_mean,
            confidence_icc=args.confidence_icc,
            **common,
        )
    else:
        frame, truth = simulate_readability(
            args.participants, args.true_rate, args.human_rate, **common
        )
    out.parent.mkdir(parents=True, exist_ok=True)
    truth_path = out.with_suffix(".truth.json")
    _write_files(
        out,
        lambda path: frame.to_csv(path, index=False),
        truth_path,
        lambda path: path.write_text(json.dumps(truth.to_dict(), indent=2) + "\n", "utf-8"),
    )
    print(
        f"{len(frame)} rows from {args.participants + args.inattentive} participants: {out} (truth: {truth_path})"
    )
    return 0


if __name__ == "__main__":  # the entry point's parser and error handling, with these commands
    from studies.program import main

    sys.exit(main([register]))
