"""Build a study's static web folder: stimuli, counterbalanced trial list, pages.

:func:`build_study` (behind ``prg-study build``) writes ``studies/<name>/build/``::

    index.html, study.js, study.css   the questionnaire (dependency-free; runs from file://)
    common.js, common.css             what the questionnaire and the capture page share
    config.js / config.json           page settings: columns, completion code and URL, saving
    trials.js / trials.json           one counterbalanced row per participant, with ground truth
    trials.csv                        the same, one line per stimulus shown (long format)
    stim/<opaque>.png                 every sample, drawn alike (studies.stimuli)
    stimuli.csv                       which PNG is which word, writer and source file
    capture/                          the capture page for the human writers (index.html, ...)
    sources/robot/<word>.json         the robot's word trajectories
    manifest.json                     what was built, what is missing, app_version
    README.md                         how to host it and the URL parameters

Everything is written into a hidden folder beside the target and renamed into place at the end.
Without enough human samples the build is *not ready*: it still writes the robot stimuli and the
capture page, and the questionnaire page says what is missing (``BuildReport.missing``).

A *pilot* build (``pilot=True``, ``prg-study build --pilot``; default folder
``studies/<name>/pilot/``) runs end to end before the human writers have written: stand-ins made
from the robot's samples replace the missing ones. It is kept apart from a study's data: every
page shows a PILOT banner (and "PILOT" in its title), ``app_version`` ends in ``-pilot`` (the
analysis refuses to mix such rows with others), the answers are never POSTed (download only, in a
file named ``PILOT_...``) and its completion code starts with ``PILOT-``.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import shutil
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import prg
from prg.errors import UsageError
from prg.files import staged_folder
from prg.resources import project_path
from studies.design import Row, balance_notes, design_rows
from studies.design_config import StudySettings
from studies.pages import (
    CAPTURE_ASSETS,
    PAGES,
    PILOT_SUFFIX,
    STUDY_ASSETS,
    js_assignment,
    page_config,
    page_html,
    pilot_banner,
    readme,
    response_columns,
    web_asset,
)
from studies.stimuli import (
    ROBOT,
    HumanSamples,
    RenderStyle,
    Sample,
    generate_robot_words,
    held_out_words,
    load_human_samples,
    load_robot_words,
    render_sample,
    save_png,
    stand_ins,
    stimulus_name,
    unmarked_words,
)


@dataclass
class BuildReport:
    """What :func:`build_study` wrote.

    Attributes
    ----------
    out_dir : Path
    ready : bool
        The questionnaire can run (every word has its human writers, or stand-ins in a
        pilot build).
    pilot : bool
        A pilot build: try the pages, do not collect data (see the module docstring).
    missing : list of str
        What is missing before it can, one line each.
    notes : list of str
        Where counterbalancing is only near-exact; human samples left out, and why.
    n_stimuli : int
    app_version : str
    stand_ins : int
        Stand-in samples a pilot build made for the missing human ones.
    """

    out_dir: Path
    ready: bool
    pilot: bool = False
    missing: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    n_stimuli: int = 0
    app_version: str = ""
    stand_ins: int = 0


def default_out(name: str, pilot: bool = False) -> Path:
    """Where ``prg-study build`` writes a study by default: ``studies/<name>/build``, or
    ``studies/<name>/pilot`` for a pilot build (never over the real one)."""
    return Path("studies") / name / ("pilot" if pilot else "build")


def choose_writers(config: StudySettings, humans: HumanSamples) -> tuple[dict, list[str]]:
    """The human writers used per word (first ``human_writers`` in sorted order) and what is
    missing."""
    used: dict[str, list[str]] = {}
    short: dict[int, list[str]] = {}
    for word in config.words:
        ids = sorted(humans.by_word.get(word, {}))
        used[word] = ids[: config.human_writers]
        if len(ids) < config.human_writers:
            short.setdefault(len(ids), []).append(word)
    missing = [
        f"{', '.join(words)}: {n} of {config.human_writers} human writers each (record more "
        "with capture/index.html, then rebuild with --human DIR)"
        for n, words in sorted(short.items())
    ]
    return used, missing


def trial_table(rows: Sequence[Row], files: dict[tuple[str, str], str]) -> str:
    """``trials.csv``: one line per stimulus of every trial of every row (ground truth)."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(
        [
            "row",
            "list_id",
            "trial",
            "word",
            "position",
            "writer_id",
            "source",
            "file",
            "is_robot_position",
            "is_attention_check",
        ]
    )
    for row in rows:
        for i, trial in enumerate(row.trials):
            for pos, writer in enumerate(trial.options):
                w.writerow(
                    [
                        row.row + 1,
                        row.list_id,
                        i,
                        trial.word,
                        pos,
                        writer,
                        ROBOT if writer == ROBOT else "human",
                        files[(trial.word, writer)],
                        "true" if writer == ROBOT else "false",
                        "true" if trial.is_attention_check else "false",
                    ]
                )
    return out.getvalue()


def rows_document(rows: Sequence[Row], files: dict[tuple[str, str], str]) -> dict:
    """``trials.json``: the rows as the page reads them."""
    doc_rows = []
    for row in rows:
        trials = []
        for trial in row.trials:
            item = {
                "word": trial.word,
                "stimuli": [files[(trial.word, w)] for w in trial.options],
                "writers": list(trial.options),
                "is_attention_check": trial.is_attention_check,
            }
            if trial.robot_index is not None:
                item["robot_index"] = trial.robot_index
            else:
                item["writer"] = trial.writer
            if trial.is_attention_check:
                item["expect"] = trial.expect
                item["instruction"] = trial.instruction
            trials.append(item)
        doc_rows.append({"row": row.row + 1, "list_id": row.list_id, "trials": trials})
    return {"rows": doc_rows}


def _hash(*parts: bytes) -> str:
    h = hashlib.sha256()
    for part in parts:
        h.update(hashlib.sha256(part).digest())
    return h.hexdigest()


def build_study(
    config: StudySettings,
    human_dirs: Sequence[str | Path] = (),
    robot_dir: str | Path | None = None,
    ckpt: str | Path | None = None,
    out_dir: str | Path | None = None,
    progress: Callable[[str], None] | None = None,
    pilot: bool = False,
    pilot_data: str | Path | None = None,
) -> BuildReport:
    """Build the study's web folder (see the module docstring).

    Parameters
    ----------
    config : StudySettings
    human_dirs : sequence of path
        Folders of human samples (capture JSON, strokes JSON, SVG), added to the config's
        ``human.dirs``.
    robot_dir : path, optional
        Ready word trajectories (``<word>.json`` or ``<word>/word.json``); default: the
        config's ``robot.dir``, else each word is written now with ``prg-write``'s task.
    ckpt : path, optional
        Checkpoint for writing the robot's words (default: the config's ``robot.ckpt``, else
        ``models/<robot.family>/model.ckpt``).
    out_dir : path, optional
        Default :func:`default_out` (relative to the working directory).
    progress : callable, optional
        Called with one line per step.
    pilot : bool
        A pilot build (see the module docstring): missing human samples are filled with
        held-out writers' words (:func:`studies.stimuli.held_out_words`, from ``pilot_data``)
        or, without that dataset, stand-ins made from the robot's
        (:func:`studies.stimuli.stand_ins`), so the pages (and ``prg-study judge``) can be
        tried before the human writers have written; default folder ``studies/<name>/pilot``.
    pilot_data : path, optional
        A prepared dataset folder (its ``test.npz``) for a pilot's human words.

    Returns
    -------
    BuildReport

    Raises
    ------
    UsageError
        A folder or file that cannot be read, a bad render setting, a missing checkpoint; a
        pilot build into a folder that holds a study's own build.
    """
    say = progress or (lambda line: None)
    style = RenderStyle.from_dict(config.render)
    out = Path(out_dir) if out_dir is not None else default_out(config.name, pilot)
    if pilot and _holds_a_study_build(out):
        raise UsageError(
            f"--out {out}: holds a study's own build (its manifest.json says pilot: false); "
            f"a pilot build goes to a folder of its own, e.g. the default "
            f"{default_out(config.name, pilot=True)}"
        )
    # a real build in its default folder points its not-ready page at the pilot copy beside it
    pilot_copy = None
    if not pilot and out.resolve() == default_out(config.name).resolve():
        pilot_copy = "../pilot/index.html"
    with staged_folder(out) as staging:
        report = _build_into(
            staging, config, style, human_dirs, robot_dir, ckpt, say, pilot, pilot_copy, pilot_data
        )
    report.out_dir = out
    return report


def _build_into(
    root: Path,
    config: StudySettings,
    style: RenderStyle,
    human_dirs: Sequence[str | Path],
    robot_dir: str | Path | None,
    ckpt: str | Path | None,
    say: Callable[[str], None],
    pilot: bool,
    pilot_copy: str | None,
    pilot_data: str | Path | None = None,
) -> BuildReport:
    # human samples first: a bad folder or file fails before the model runs
    dirs = [*(config.human.get("dirs") or []), *human_dirs]
    delayed = config.delayed_strokes
    humans = load_human_samples(
        dirs, config.words, bool(config.human["accept_lifted"]), delayed_strokes=delayed
    )

    # robot samples
    sources = root / "sources" / "robot"
    robot_dir = robot_dir if robot_dir is not None else config.robot.get("dir")
    robot_notes = []
    if robot_dir is not None:
        robot = load_robot_words(robot_dir, config.words, delayed_strokes=delayed)
        sources.mkdir(parents=True)
        for word, sample in robot.items():
            shutil.copyfile(sample.origin, sources / f"{word}.json")
        unmarked = unmarked_words(robot) if delayed else []
        if unmarked:
            robot_notes.append(
                f"robot words without delayed strokes (dots, bars) although delayed_strokes "
                f"is true: {', '.join(unmarked)}; the human writers are asked to add theirs "
                f"(rewrite them with prg-write delayed_strokes=true, or set "
                "delayed_strokes: false)"
            )
    else:
        generate_robot_words(
            config.words,
            sources,
            family=config.robot["family"],
            ckpt=ckpt if ckpt is not None else config.robot.get("ckpt"),
            overrides=config.robot["write_overrides"],
            progress=say,
            delayed_strokes=delayed,
            hand_per_word=config.robot["hands"] == "per_word",
        )
        robot = load_robot_words(sources, config.words, delayed_strokes=delayed)

    # what the design may show
    writers, missing = choose_writers(config, humans)
    if not dirs:
        missing = [
            f"no human samples were given: each of the {len(config.words)} words needs "
            f"{config.human_writers} human writers; record them with capture/index.html and "
            "rebuild with --human DIR (or list the folders in human.dirs)"
        ]
    n_stand_ins = 0
    if pilot:  # stand-ins for the missing writers: held-out writers' letters, or the robot's
        short = {w: max(0, config.human_writers - len(writers[w])) for w in config.words}
        data = Path(pilot_data) if pilot_data is not None else None
        if data is not None and (data / "test.npz").is_file() and max(short.values()) > 0:
            made = held_out_words(
                config.words,
                max(short.values()),
                data,
                root / "sources" / "pilot",
                config.seed,
                delayed_strokes=delayed,
            )
            filled = {w: made[w][: short[w]] for w in config.words}
        else:
            filled = {
                w: stand_ins(robot[w], short[w], config.seed, delayed_strokes=delayed)
                for w in config.words
            }
        for word in config.words:
            for sample in filled[word]:
                humans.by_word[word][sample.writer_id] = sample
                writers[word].append(sample.writer_id)
                n_stand_ins += 1
    ready = pilot or not missing

    # stimuli: every sample the design may show, drawn alike, under opaque names
    samples: list[Sample] = list(robot.values())
    for word in config.words:
        samples.extend(humans.by_word[word][w] for w in writers[word])
    files: dict[tuple[str, str], str] = {}
    table = io.StringIO()
    stim_csv = csv.writer(table, lineterminator="\n")
    stim_csv.writerow(["file", "word", "writer_id", "source", "origin"])
    for i, sample in enumerate(samples):
        name = f"stim/{stimulus_name(sample, f'{config.name}:{config.seed}')}"
        save_png(render_sample(sample, style), root / name)
        files[(sample.word, sample.writer_id)] = name
        origin = Path(sample.origin)
        if origin.is_relative_to(root):
            origin = origin.relative_to(root)
        stim_csv.writerow([name, sample.word, sample.writer_id, sample.source, origin.as_posix()])
        if (i + 1) % 20 == 0 or i + 1 == len(samples):
            say(f"stimuli drawn: {i + 1}/{len(samples)}")
    (root / "stimuli.csv").write_text(table.getvalue(), encoding="utf-8")

    # the design
    rows = design_rows(config, writers) if ready else ()
    trials = rows_document(rows, files)
    (root / "trials.csv").write_text(trial_table(rows, files), encoding="utf-8")

    # pages
    banners = {page: pilot_banner(n_stand_ins, page) if pilot else None for page in PAGES}
    assets = {"index.html": page_html("study", banners["study"])}
    assets |= {dst: web_asset(src) for src, dst in STUDY_ASSETS.items()}
    capture_assets = {"index.html": page_html("capture", banners["capture"])}
    capture_assets |= {dst: web_asset(src) for src, dst in CAPTURE_ASSETS.items()}
    digest = _hash(
        json.dumps(trials, sort_keys=True).encode(),
        json.dumps(
            page_config(config, "", ready, missing, pilot, pilot_copy), sort_keys=True
        ).encode(),
        *assets.values(),
    )
    app_version = f"{prg.__version__}+{digest[:10]}" + (PILOT_SUFFIX if pilot else "")
    page = page_config(config, app_version, ready, missing, pilot, pilot_copy)
    for name, data in assets.items():
        (root / name).write_bytes(data)
    (root / "config.js").write_text(js_assignment("PRG_STUDY_CONFIG", page), encoding="utf-8")
    (root / "trials.js").write_text(js_assignment("PRG_STUDY_TRIALS", trials), encoding="utf-8")
    _write_json(root / "config.json", page)
    _write_json(root / "trials.json", trials)
    capture = root / "capture"
    capture.mkdir()
    for name, data in capture_assets.items():
        (capture / name).write_bytes(data)
    capture_cfg = {
        "study": config.name,
        "words": list(config.words),
        "on_lift": config.capture["on_lift"],
        "delayed_strokes": delayed,
        "delayed_max_size": float(config.capture["delayed_max_size"]),
        "post_url": config.capture["post_url"],
        "canvas_width": int(config.capture["canvas_width"]),
        "canvas_height": int(config.capture["canvas_height"]),
        "app_version": app_version,
        "pilot": pilot,
    }
    (capture / "config.js").write_text(
        js_assignment("PRG_CAPTURE_CONFIG", capture_cfg), encoding="utf-8"
    )
    notes = [*balance_notes(config), *robot_notes, *humans.notes]
    report = BuildReport(root, ready, pilot, missing, notes, len(samples), app_version, n_stand_ins)
    _write_json(
        root / "manifest.json",
        {
            "study": config.name,
            "kind": config.kind,
            "source": config.source,
            "app_version": app_version,
            "seed": config.seed,
            "delayed_strokes": delayed,
            "ready": ready,
            "pilot": pilot,
            "stand_ins": n_stand_ins,
            "missing": missing,
            "notes": notes,
            "words": list(config.words),
            "participants": len(rows),
            "stimuli": len(samples),
            "human_writers": {w: writers[w] for w in config.words},
            "render": vars(style),
            "robot": {  # how the robot's words were written (prg-study judge writes more)
                **config.robot,
                # project files named from the project root (the manifest travels)
                "ckpt": _shown(ckpt) if ckpt is not None else config.robot["ckpt"],
                "dir": _shown(robot_dir) if robot_dir is not None else None,
            },
            "columns": list(response_columns(config.kind)),
        },
    )
    (root / "README.md").write_text(
        readme(config, page, default_out(config.name, pilot=True)), encoding="utf-8"
    )
    return report


def _holds_a_study_build(folder: Path) -> bool:
    """``folder`` holds a build that is not a pilot (by its ``manifest.json``)."""
    try:
        manifest = json.loads((folder / "manifest.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return isinstance(manifest, dict) and manifest.get("pilot") is False


def _write_json(path: Path, obj) -> None:
    path.write_text(json.dumps(obj, indent=1, sort_keys=True, ensure_ascii=False) + "\n")


def _shown(path: str | Path) -> str:
    """``path`` as the manifest names it: from the project root when inside the project
    (:func:`prg.resources.project_path`), absolute otherwise."""
    from prg.commands.cli import project_root

    return project_path(path, project_root()[0])
