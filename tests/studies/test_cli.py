"""Boundary studies through ``prg-study analyze``: every answer the same, participants and words at
0 % and 100 %, perfect separation of the writers. Each must exit 0 and write a report in which a
model that cannot be fitted says so (no estimate, NaN p, the reason) and every interval contains
its rate and stays inside [0, 1]."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from studies.analysis.participants import simulate_readability, simulate_turing
from studies.cli import main
from studies.judge import judge
from tests.helpers.browser import human_dir, robot_dir
from tests.helpers.study_judge import _build
from tests.helpers.study_web import REPO, TURING, WORDS, build, capture, samples  # noqa: F401 (fixtures)

N = 24  # participants: enough for the GEE (>= 20 clusters) and quick


def _answered(frame: pd.DataFrame) -> pd.Series:
    return frame["is_attention_check"].astype(str) != "true"


def set_turing(frame: pd.DataFrame, where: pd.Series, picked_robot: bool) -> None:
    """Rows ``where`` (not attention checks) pick the robot's sample, or a human's."""
    m = where & _answered(frame)
    robot = frame.loc[m, "robot_index"].astype(int)
    frame.loc[m, "chosen_index"] = robot if picked_robot else (robot + 1) % 5
    frame.loc[m, "chose_robot"] = "true" if picked_robot else "false"


def set_readability(frame: pd.DataFrame, where: pd.Series, correct: bool) -> None:
    m = where & _answered(frame)
    frame.loc[m, "typed_text"] = frame.loc[m, "word"] if correct else "???"
    frame.loc[m, "correct"] = "true" if correct else "false"


def turing(case: str) -> pd.DataFrame:
    frame, _ = simulate_turing(N, 0.3, seed=5)
    everyone = pd.Series(True, index=frame.index)
    people = sorted(frame["participant_id"].unique())
    words = sorted(frame.loc[_answered(frame), "word"].unique())
    if case in ("all-robot", "all-human"):
        set_turing(frame, everyone, case == "all-robot")
        rating = 5 if case == "all-robot" else 3  # every rating the same too
        frame.loc[_answered(frame), "confidence"] = rating
    elif case == "participants-0-100":
        set_turing(frame, frame["participant_id"].isin(people[:4]), True)
        set_turing(frame, frame["participant_id"].isin(people[4:8]), False)
    elif case == "words-0-100":
        set_turing(frame, frame["word"] == words[0], True)
        set_turing(frame, frame["word"] == words[1], False)
    return frame


def readability(case: str) -> pd.DataFrame:
    frame, _ = simulate_readability(N, 0.7, seed=6)
    everyone = pd.Series(True, index=frame.index)
    people = sorted(frame["participant_id"].unique())
    words = sorted(frame.loc[_answered(frame), "word"].unique())
    robot = frame["writer"] == "robot"
    if case in ("all-correct", "all-wrong"):
        set_readability(frame, everyone, case == "all-correct")
    elif case == "separation":  # every robot word read, no human word
        set_readability(frame, robot, True)
        set_readability(frame, ~robot, False)
    elif case == "robot-all-correct":  # quasi-separation: the human's answers vary
        set_readability(frame, robot, True)
    elif case == "participants-0-100":
        set_readability(frame, frame["participant_id"].isin(people[:4]), True)
        set_readability(frame, frame["participant_id"].isin(people[4:8]), False)
    elif case == "words-0-100":
        set_readability(frame, frame["word"] == words[0], True)
        set_readability(frame, frame["word"] == words[1], False)
    return frame


def analyze(tmp_path: Path, frame: pd.DataFrame, capsys) -> Path:
    src = tmp_path / "responses.csv"
    frame.to_csv(src, index=False)
    out = tmp_path / "report"
    code = main(["analyze", str(src), "--out", str(out), "--no-paper"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "Traceback" not in captured.err
    assert (out / "report.html").is_file() and (out / "report.md").is_file()
    return out


def check_report(out: Path) -> tuple[pd.DataFrame, dict]:
    """The statistical invariants every report must hold, boundary or not."""
    tests = pd.read_csv(out / "tests.csv")
    for r in tests.itertuples(index=False):
        where = f"{r.test}: {r.conclusion}"
        if math.isfinite(r.p_value):
            assert 0 < r.p_value <= 1, where  # p = 0 is a division by a zero SE, not a test
            if not r.test.startswith("Wilcoxon"):  # the only test without an interval
                assert r.ci_low < r.ci_high and r.ci_low <= r.estimate <= r.ci_high, where
            assert not str(r.conclusion).startswith("not estimable"), where
        else:
            assert str(r.conclusion).startswith("not estimable: "), where
            assert len(str(r.conclusion)) > len("not estimable: ") + 10, where  # a reason
            assert not math.isfinite(r.ci_low) and not math.isfinite(r.ci_high), where
        if "rate" in str(r.null_hypothesis) and "-" not in r.test and math.isfinite(r.ci_low):
            assert r.ci_low >= 0 and r.ci_high <= 1, where
    for name in ("per_word.csv", "per_participant.csv"):
        table = pd.read_csv(out / name)
        assert ((table.ci_low <= table.rate) & (table.rate <= table.ci_high)).all(), name
        assert ((table.ci_low >= 0) & (table.ci_high <= 1)).all(), name
        assert (table.ci_low < table.ci_high).all(), name  # a rate of 0 or 1 is not certain
    mixed = pd.read_csv(out / "mixed_model.csv")
    status = str(mixed.status.iloc[0])
    if not status.startswith(("ok", "converged")):
        assert status.startswith(("failed: ", "skipped: ")) and len(mixed) == 1, status
    md = (out / "report.md").read_text("utf-8")
    assert " nan" not in md.lower() and "p = 0 " not in md and "p = 0)" not in md
    return tests, json.loads((out / "metrics.json").read_text("utf-8"))


def row(tests: pd.DataFrame, start: str) -> pd.Series:
    hit = tests[tests.test.str.startswith(start)]
    assert len(hit), start
    return hit.iloc[0]


@pytest.mark.filterwarnings("error::RuntimeWarning")  # e.g. scipy's "catastrophic cancellation"
@pytest.mark.parametrize("case", ["all-robot", "all-human"])
def test_turing_study_where_every_answer_is_the_same(tmp_path, capsys, case):
    out = analyze(tmp_path, turing(case), capsys)
    tests, metrics = check_report(out)
    y = 1.0 if case == "all-robot" else 0.0
    for name in ("GEE rate vs chance", "GEE TOST vs chance", "one-sample t-test vs 0.2"):
        assert np.isnan(row(tests, name).p_value), name  # infinite log-odds, no spread
    exact = row(tests, "exact binomial test vs chance")
    assert exact.estimate == y and exact.ci_low < exact.ci_high
    assert (exact.ci_high if y else exact.ci_low) == y  # the bound is the rate itself
    for name in ("one-sample t-test vs 3 on ratings", "one-sample t-test vs 3 on participant"):
        assert np.isnan(row(tests, name).p_value), name  # every rating the same
    verdict = metrics["studies"]["turing"]
    assert verdict["h1"] == "not estimable" and "log-odds are infinite" in verdict["h1_reason"]
    assert verdict["h2"] == "not estimable" and "zero variance" in verdict["h2_reason"]
    status = pd.read_csv(out / "mixed_model.csv").status.iloc[0]
    assert status.startswith(f"failed: every answer is {y:g}")
    summary = (out / "report.md").read_text("utf-8")
    assert "**H1**: not estimable from these data:" in summary
    assert "**H2**: not estimable" in summary


@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("case", ["participants-0-100", "words-0-100"])
def test_turing_participants_and_words_at_0_and_100_percent(tmp_path, capsys, case):
    out = analyze(tmp_path, turing(case), capsys)
    tests, metrics = check_report(out)
    gee = row(tests, "GEE rate vs chance")
    assert np.isfinite(gee.p_value)  # a few people or words at 0/100 % is no separation
    assert metrics["studies"]["turing"]["h1"] != "not estimable"
    by = "per_participant.csv" if case.startswith("participants") else "per_word.csv"
    table = pd.read_csv(out / by)
    assert {0.0, 1.0} <= set(table.rate)
    assert (table[table.rate == 0].ci_low == 0).all() and (
        table[table.rate == 1].ci_high == 1
    ).all()


@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("case", ["all-correct", "all-wrong", "separation"])
def test_readability_study_without_variation_is_reported_not_estimable(tmp_path, capsys, case):
    out = analyze(tmp_path, readability(case), capsys)
    tests, metrics = check_report(out)
    for name in (
        "independent t-test on word rates",
        "paired t-test by participant",
        "GEE difference",
        "paired t-test by word",
    ):
        assert np.isnan(row(tests, name).p_value), name
    verdict = metrics["studies"]["readability"]
    assert verdict["verdict"] == "not estimable" and "zero variance" in verdict["reason"]
    status = pd.read_csv(out / "mixed_model.csv").status.iloc[0]
    assert status.startswith("failed: ")
    if case == "separation":
        assert "perfect separation" in row(tests, "GEE difference").conclusion
        assert "separation" in status
    assert "**Readability**: not estimable from these data:" in (out / "report.md").read_text()


@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("case", ["robot-all-correct", "participants-0-100", "words-0-100"])
def test_readability_participants_words_and_one_writer_at_the_boundary(tmp_path, capsys, case):
    out = analyze(tmp_path, readability(case), capsys)
    tests, metrics = check_report(out)
    paired = row(tests, "paired t-test by participant")
    assert np.isfinite(paired.p_value)  # the paired differences still vary
    assert metrics["studies"]["readability"]["verdict"] != "not estimable"
    status = pd.read_csv(out / "mixed_model.csv").status.iloc[0]
    if case == "robot-all-correct":  # the writer effect's log-odds are infinite
        assert status.startswith("failed: separation: every robot answer is 1")
        assert "every robot answer is 1" in row(tests, "GEE difference").method
    else:
        table = pd.read_csv(
            out / ("per_word.csv" if case.startswith("words") else "per_participant.csv")
        )
        assert {0.0, 1.0} <= set(table.rate)


def test_a_turing_margin_that_leaves_zero_to_one_is_refused_before_anything_is_written(
    tmp_path, capsys
):
    src = tmp_path / "responses.csv"
    turing("participants-0-100").to_csv(src, index=False)
    out = tmp_path / "report"
    assert main(["analyze", str(src), "--margin", "0.5", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("prg-study: error: chance 0.2 ± "), err
    assert "--margin" in err[0] and not out.exists()


# A study file (YAML) with one bad setting: each class of nonsense, refused by `prg-study build`
# with one line naming the setting and what is accepted, exit 2, nothing written.
FILE_CASES = [
    # negative or zero counts, rates and durations
    ("participants", -4, "participants must be an integer from 1 to"),
    ("human_writers", 0, "human_writers must be an integer from 1 to"),
    ("alpha", -0.05, "alpha must be a number in"),
    ("equivalence_margin", 0, "equivalence_margin must be a number in"),
    ("analysis.equivalence_margin", -0.2, "analysis: equivalence_margin -0.2 is outside"),
    ("completion.redirect_delay_ms", -1, "redirect_delay_ms must be an integer from 0 to"),
    ("render.stroke_px", -2.0, "render.stroke_px must be a positive finite number"),
    # NaN and infinity
    ("alpha", float("nan"), "alpha must be a number in"),
    ("analysis.alpha", float("inf"), "analysis: alpha inf is outside"),
    ("participants", float("nan"), "participants must be an integer"),
    ("render.stroke_px", float("inf"), "render.stroke_px must be a positive finite number"),
    ("completion.redirect_delay_ms", float("nan"), "redirect_delay_ms must be an integer"),
    # canvases and images of no (or absurd) size
    ("capture.canvas_width", 0, "capture.canvas_width must be an integer from 50 to"),
    ("capture.canvas_height", 0, "capture.canvas_height must be an integer from 50 to"),
    ("render.height_px", 0, "render.height_px must be an integer from 1 to"),
    ("render.supersample", 100, "render.supersample must be an integer from 1 to 8"),
    # completion and upload URLs: http(s) only, the completion URL with its {code}
    ("completion.url", "https://example.org/done", "has no {code} placeholder"),
    ("completion.url", "javascript:alert(1)//{code}", "completion.url must be an http:// or"),
    ("completion.url", "data:text/html,<b>{code}</b>", "completion.url must be an http:// or"),
    ("save.post_url", "file:///etc/passwd", "save.post_url must be an http:// or"),
    ("capture.post_url", "https://", "capture.post_url must be an http:// or"),
    ("completion.code", "a b&c", "completion.code must be 1-64 letters"),
    # huge values: refused with the limit
    ("participants", 10**9, "participants must be an integer from 1 to 10000"),
    ("seed", 10**30, "seed must be an integer from 0 to"),
    ("words", [f"w{'a' * (i % 7)}{chr(97 + i % 26)}" for i in range(300)], "1 to 200 words"),
    ("render.width_px", 10**6, "render.width_px must be an integer from 1 to 4000"),
    ("foils", 1000, "foils must be an integer from 1 to 9"),
    # settings of the wrong type or name
    ("save.download", "maybe", "save.download must be true or false"),
    ("delayed_strokes", "yes please", "delayed_strokes must be true"),
    ("delayed_strokes", 0, "delayed_strokes must be true"),
    ("capture.delayed_max_size", float("nan"), "capture.delayed_max_size must be a number"),
    ("capture.delayed_max_size", "0.3", "capture.delayed_max_size must be a number"),
    ("page.title", 5, "page.title must be text"),
    ("completion.colour", "red", "completion: unknown key 'colour'"),
    ("analysis.alhpa", 0.1, "analysis: unknown key 'alhpa'"),
]


@pytest.mark.parametrize(
    ("key", "value", "message"), FILE_CASES, ids=[f"{k}={str(v)[:20]}" for k, v, _ in FILE_CASES]
)
def test_bad_study_files_are_one_line_exit_2_and_build_nothing(
    key, value, message, tmp_path, capsys
):
    import yaml

    from studies.cli import main

    doc = yaml.safe_load((REPO / "conf/study/turing.yaml").read_text())
    *sections, last = key.split(".")
    node = doc
    for section in sections:
        node = node.setdefault(section, {})
    node[last] = value
    study = tmp_path / "study.yaml"
    study.write_text(yaml.safe_dump(doc))
    out = tmp_path / "build"
    assert main(["build", str(study), "--out", str(out), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"prg-study: error: {study}: "), err
    assert message in err[0]
    assert not out.exists()


def test_the_command_prints_the_result_and_refuses_a_folder_that_is_no_study(tmp_path, capsys):
    assert main(["judge", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "not a built study" in err and len(err.strip().splitlines()) == 1


def test_the_judge_goes_into_the_study_report(tmp_path):
    humans = human_dir(tmp_path / "human", WORDS, 5, seed=2)
    folder = _build(tmp_path / "study", robot_dir(tmp_path / "robot", WORDS), humans, writers=5)
    result = judge(folder, trials_per_word=20)
    responses = tmp_path / "sim.csv"
    study = str(REPO / "conf/study/turing.yaml")
    args = ["simulate", "turing", "--participants", "8", "--true-rate", "0.3"]
    assert main([*args, "--study", study, "--out", str(responses)]) == 0
    out = tmp_path / "report"
    analyze = ["analyze", str(responses), "--study", study, "--out", str(out), "--no-mixed"]
    assert main([*analyze, "--no-paper", "--judge", str(folder / "judge.json")]) == 0
    text = (out / "report.md").read_text()
    assert "the automatic judge" in text and f"{result['observer']['pick_rate']:.2f}" in text
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["judge"]["observer_pick_rate"] == pytest.approx(result["observer"]["pick_rate"])
    (tmp_path / "bad.json").write_text("{}")
    assert main([*analyze, "--judge", str(tmp_path / "bad.json")]) == 2


def test_a_pilot_data_folder_without_a_dataset_is_one_clear_error(tmp_path, capsys):
    args = ["build", str(REPO / "conf/study/turing.yaml"), "--pilot", "--out", str(tmp_path / "p")]
    assert main([*args, "--pilot-data", str(tmp_path), "-q"]) == 2
    assert "--pilot-data" in capsys.readouterr().err and not (tmp_path / "p").exists()


# ---------------------------------------------------------------------------- prg-study build
def read_js_config(path: Path) -> dict:
    """The object that a ``config.js`` (``window.X = {...};``) assigns."""
    text = path.read_text()
    return json.loads(text[text.index("=") + 1 :].strip().rstrip(";"))


@pytest.mark.parametrize("delayed", [True, False])
def test_the_robot_writes_and_the_writers_are_asked_as_delayed_strokes_says(
    tmp_path, untrained_muse_checkpoint, delayed
):
    from prg.pipeline.word import WordTrajectory

    out = tmp_path / "b"
    args = ["build", str(REPO / TURING), "--out", str(out), "-q", "--pilot"]
    args += ["--ckpt", str(untrained_muse_checkpoint)]
    for setting in (
        "words=[it, cat]",
        "attention_checks=[]",
        "participants=2",
        f"delayed_strokes={str(delayed).lower()}",
    ):
        args += ["--set", setting]
    assert main(args) == 0
    marks = {
        w: WordTrajectory.from_json(out / "sources" / "robot" / f"{w}.json").segment_kinds.count(
            "mark"
        )
        for w in ("it", "cat")
    }
    assert marks == ({"it": 2, "cat": 1} if delayed else {"it": 0, "cat": 0})
    assert read_js_config(out / "capture" / "config.js")["delayed_strokes"] is delayed
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["delayed_strokes"] is delayed and manifest["pilot"] is True
    assert json.loads((out / "config.json").read_text())["delayed_strokes"] is delayed


@pytest.mark.parametrize("delayed", [True, False])
def test_ready_robot_words_without_marks_are_noted_when_delayed_strokes_are_on(
    tmp_path, samples, capsys, delayed
):
    build(
        tmp_path / "b", "turing", f"delayed_strokes={str(delayed).lower()}", robot=samples["robot"]
    )
    err = capsys.readouterr().err
    noted = "robot words without delayed strokes (dots, bars) although delayed_strokes is true"
    assert (noted in err) is delayed
    if delayed:  # the study words with an i, j, t or f
        assert f"{noted}: cat, ink;" in err


def test_some_human_samples_missing_is_an_error_on_request(tmp_path, samples, capsys):
    args = [
        "build",
        str(REPO / "conf/study/turing.yaml"),
        "--out",
        str(tmp_path / "b"),
        "-q",
        "--robot",
        str(samples["robot"]),
        "--human",
        str(samples["human"]),
        "--set",
        f"words=[{', '.join(WORDS)}]",
        "--require-ready",
    ]
    assert main(args) == 2  # 5 writers, 10 wanted
    err = capsys.readouterr().err
    assert "missing: cat, dog, sun, egg, ink, owl: 5 of 10 human writers each" in err
    assert (
        err.strip().splitlines()[-1] == "prg-study: error: turing is not ready: 1 missing item(s)"
    )


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["build", "nope.yaml", "--out", "{out}"], "nope.yaml: no such study file"),
        (["build", TURING, "--out", "{out}", "--set", "foils=x"], "foils must be an integer"),
        (["build", TURING, "--out", "{out}", "--human", "/no"], "--human /no: no such folder"),
        (["build", TURING, "--out", "{out}", "--robot", "/no"], "--robot /no: no such folder"),
        (
            [
                "build",
                TURING,
                "--out",
                "{out}",
                "--robot",
                "{robot}",
                "--set",
                "render.stroke_px=0",
            ],
            "render.stroke_px must be a positive finite number",
        ),
        (["build"], "the following arguments are required: config"),
        (["build", TURING, "--bogus"], "unrecognized arguments: --bogus"),
        ([], "choose a command: build"),
    ],
)
def test_mistakes_are_one_line_with_exit_code_2(
    tmp_path, samples, args, message, capsys, monkeypatch
):
    monkeypatch.chdir(REPO)
    args = [a.format(out=tmp_path / "out", robot=samples["robot"]) for a in args]
    try:
        code = main(args)
    except SystemExit as exit_:  # argparse's own errors
        code = exit_.code
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("prg-study: error: ") and message in err
    assert sorted(tmp_path.iterdir()) == []  # nothing half-written


def test_a_failed_rebuild_leaves_the_previous_build_intact(tmp_path, samples, capsys):
    out = build(tmp_path / "b", "turing", "participants=5", **samples)
    before = (out / "trials.json").read_text()
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "x.json").write_text("{oops")
    args = [
        "build",
        str(REPO / "conf/study/turing.yaml"),
        "--out",
        str(out),
        "-q",
        "--robot",
        str(samples["robot"]),
        "--human",
        str(broken),
        "--set",
        f"words=[{', '.join(WORDS)}]",
    ]
    assert main(args) == 2
    assert "x.json: not valid JSON" in capsys.readouterr().err
    assert (out / "trials.json").read_text() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b", "broken"]  # no temporary folders


def test_the_manifest_names_project_files_from_the_project_root(tmp_path, samples, monkeypatch):
    """The robot's folder inside the project is named from the project root (the bundle is
    shared; a path of this machine would say nothing there), one outside it absolutely."""
    import shutil

    shutil.copytree(samples["robot"], tmp_path / "project" / "outputs" / "robot")
    monkeypatch.setenv("PRG_ROOT", str(tmp_path / "project"))
    out = build(tmp_path / "b", "turing", robot=tmp_path / "project" / "outputs" / "robot")
    assert json.loads((out / "manifest.json").read_text())["robot"]["dir"] == "outputs/robot"
    out = build(tmp_path / "c", "turing", robot=samples["robot"])
    assert json.loads((out / "manifest.json").read_text())["robot"]["dir"] == str(samples["robot"])
