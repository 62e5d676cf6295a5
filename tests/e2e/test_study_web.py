"""The built study folders, driven start to finish in a real headless chromium.

``prg-study build`` writes a questionnaire page (study 1 or 2) and a capture page for the human
writers. Each test drives a page the way a participant or writer would (clicks, typing, mouse
strokes) and asserts what the page saved: the response CSV that the analysis reads, the POSTed
copy, the redirect to Prolific, the capture JSON — and that JSON fed back as human samples.
"""

from __future__ import annotations

import csv
import json
import math
import subprocess
import sys
import time
from pathlib import Path
from urllib.parse import parse_qs, urlparse

import numpy as np
import pytest

from studies.analysis.schema import STUDY1_COLUMNS, STUDY2_COLUMNS
from studies.analysis.validate import ResponseFileError, load_responses
from studies.cli import main
from studies.design import assign_row, fnv1a32
from studies.pages import response_columns
from tests.helpers.browser import read_csv, robot_dir, serve
from tests.helpers.study_web import (  # noqa: F401 (fixtures)
    PROLIFIC,
    REPO,
    TURING,
    WORDS,
    build,
    capture,
    chromium,
    page,
    samples,
    write_word,
)

COLLECT = "https://collect.example.org/responses"


@pytest.fixture(scope="module")
def turing_build(tmp_path_factory, samples) -> Path:
    out = tmp_path_factory.mktemp("turing") / "build"
    return build(
        out,
        "turing",
        "participants=10",
        "completion.code=TEST-CODE",
        "completion.redirect_delay_ms=50",
        f"save.post_url={COLLECT}",
        "attention_checks=[{after_trial: 2, instruction: 'Choose sample 4 and confidence 2.',"
        " expect: {choose_sample: 4, confidence: 2}}]",
        **samples,
    )


@pytest.fixture(scope="module")
def readability_build(tmp_path_factory, samples) -> Path:
    out = tmp_path_factory.mktemp("readability") / "build"
    return build(
        out,
        "readability",
        "participants=4",
        "completion.url=null",
        "attention_checks=[{after_trial: 3, instruction: 'Type blue.',"
        " expect: {typed_text: blue}}]",
        **samples,
    )


def start(page, url: str) -> dict:
    """Consent, instructions, wait for the stimuli; returns the participant's trial row."""
    page.goto(url)
    page.check("#consent-agree")
    page.click("#consent-continue")
    page.click("#start:not([disabled])")
    return page.evaluate("PRGStudy.state.row")


def bool_(text: str) -> bool:
    assert text in ("true", "false"), text
    return text == "true"


# ---------------------------------------------------------------------------- study 1
def test_turing_study_runs_to_completion_over_http(page, turing_build):
    posted = []

    def collect(route):
        posted.append(route.request.post_data)
        route.fulfill(status=200, headers={"Access-Control-Allow-Origin": "*"}, body="ok")

    page.route(COLLECT, collect)
    trials = json.loads((turing_build / "trials.json").read_text())["rows"]
    config = json.loads((turing_build / "config.json").read_text())
    with serve(turing_build) as base:
        row = start(page, f"{base}/index.html?PROLIFIC_PID=5f8e2a&STUDY_ID=st1&SESSION_ID=se9")
        expected_row = assign_row("5f8e2a", 10, "turing")
        assert row == trials[expected_row]  # the page and Python pick the same row
        picks = []
        with page.expect_download() as download:
            for i, trial in enumerate(row["trials"]):
                assert page.text_content("#progress") == f"Trial {i + 1} of {len(WORDS) + 1}"
                if trial["is_attention_check"]:
                    assert "Choose sample 4" in page.text_content("#check-instruction")
                    choice, confidence = 3, 2
                else:  # the robot on even trials, its right-hand neighbour on odd ones
                    choice = (trial["robot_index"] + (i % 2)) % 5
                    confidence = 1 + i % 5
                picks.append((choice, confidence))
                page.click(f"[data-option='{choice + 1}']")
                assert page.is_disabled("#next")  # confidence still missing
                page.click(f"[data-confidence='{confidence}']")
                page.click("#next")
        assert page.text_content("#completion-code") == "TEST-CODE"
        page.wait_for_url(PROLIFIC)
    assert parse_qs(urlparse(page.url).query) == {"cc": ["TEST-CODE"]}
    text = Path(download.value.path()).read_bytes().decode("utf-8")
    assert download.value.suggested_filename.startswith("turing_5f8e2a_")
    assert posted == [text]  # the same file, byte for byte (RFC 4180 line ends)

    columns, rows = read_csv(text)
    assert columns == [*STUDY1_COLUMNS, "study_id"] == list(response_columns("turing"))
    assert columns == config["columns"]
    assert len(rows) == len(row["trials"]) == len(WORDS) + 1
    for i, (r, trial, (choice, confidence)) in enumerate(zip(rows, row["trials"], picks)):
        assert (r["participant_id"], r["study_id"], r["session_id"]) == ("5f8e2a", "st1", "se9")
        assert (r["study"], r["list_id"], r["trial"]) == ("turing", row["list_id"], str(i))
        assert r["word"] == trial["word"]
        assert int(r["robot_index"]) == trial["robot_index"]
        assert trial["writers"][trial["robot_index"]] == "robot"
        assert int(r["chosen_index"]) == choice and int(r["confidence"]) == confidence
        assert bool_(r["chose_robot"]) == (choice == trial["robot_index"])
        assert bool_(r["is_attention_check"]) == trial["is_attention_check"]
        assert r["attention_pass"] == ("true" if trial["is_attention_check"] else "")
        assert float(r["rt_ms"]) >= 0
        assert r["timestamp"].endswith("Z") and r["app_version"] == config["app_version"]
        assert r["seed"] == "2022"
    assert [r["is_attention_check"] for r in rows].count("true") == 1
    assert rows[2]["is_attention_check"] == "true"
    assert sorted(r["word"] for r in rows if r["is_attention_check"] == "false") == sorted(WORDS)
    read = load_responses(download.value.path())  # what prg-study analyze reads
    assert read.kinds == ["turing"] and len(read.frame) == len(rows)


def test_page_hash_matches_python_and_row_parameter_wins(page, turing_build):
    page.goto((turing_build / "index.html").as_uri() + "?PROLIFIC_PID=abc&row=7")
    for text in ["", "a", "foobar", "turing:5f8e2a", "ünï©ødé"]:
        assert page.evaluate("t => PRGStudy.fnv1a32(t)", text) == fnv1a32(text)
    page.check("#consent-agree")
    page.click("#consent-continue")
    assert page.evaluate("PRGStudy.state.row.list_id") == "row-007"
    assert page.evaluate("PRGStudy.state.assignment") == "url"


def test_a_failed_post_keeps_the_participant_with_their_answers(page, turing_build):
    page.route(COLLECT, lambda route: route.fulfill(status=500, body="down"))
    row = start(page, (turing_build / "index.html").as_uri() + "?PROLIFIC_PID=p2&row=1")
    with page.expect_download() as download:
        for _ in row["trials"]:
            page.click("[data-option='1']")
            page.click("[data-confidence='3']")
            page.click("#next")
    page.wait_for_function("PRGStudy.state.saved === false", timeout=10_000)
    assert "could not be sent" in page.text_content("#save-status")
    page.wait_for_timeout(300)  # longer than the redirect delay: no redirect
    assert page.url.startswith("file://")
    _, rows = read_csv(Path(download.value.path()).read_text())
    assert len(rows) == len(row["trials"]) and {r["chosen_index"] for r in rows} == {"0"}
    failed = [r for r in rows if r["is_attention_check"] == "true"]
    assert [r["attention_pass"] for r in failed] == ["false"]


def test_declining_consent_records_nothing(page, turing_build):
    page.goto((turing_build / "index.html").as_uri())
    assert page.is_disabled("#consent-continue")
    page.click("#consent-decline")
    assert "no answers were recorded" in page.text_content("#declined")
    assert page.evaluate("PRGStudy.state.records.length") == 0


# ---------------------------------------------------------------------------- study 2
def test_readability_study_runs_from_a_file_url(page, readability_build):
    trials = json.loads((readability_build / "trials.json").read_text())["rows"]
    row = start(page, (readability_build / "index.html").as_uri() + "?row=2&SESSION_ID=s")
    assert row == trials[1] and row["list_id"] == "B"
    typed = []
    with page.expect_download() as download:
        for i, trial in enumerate(row["trials"]):
            assert page.is_disabled("#next")
            if trial["is_attention_check"]:
                answer = "blue"
            elif i == 0:
                answer = None  # "I can't read it"
            elif i % 2:
                answer = f"  {trial['word'].upper()} "  # right, in capitals with spaces
            else:
                answer = trial["word"] + "x"  # wrong
            typed.append(answer)
            if answer is None:
                page.click("#cannot-read")
            else:
                page.fill("#answer", answer)
                page.press("#answer", "Enter")
    assert (
        page.text_content("#completion-code")
        == json.loads((readability_build / "config.json").read_text())["completion"]["code"]
    )
    assert page.locator("#finish").count() == 0  # no completion URL: no redirect
    columns, rows = read_csv(Path(download.value.path()).read_text())
    assert columns == [*STUDY2_COLUMNS, "study_id"]
    assert len(rows) == len(WORDS) + 1
    for r, trial, answer in zip(rows, row["trials"], typed):
        assert r["participant_id"].startswith("anon-") and r["session_id"] == "s"
        assert (r["study"], r["list_id"], r["word"]) == ("readability", "B", trial["word"])
        assert (
            r["writer"]
            == trial["writer"]
            == ("robot" if trial["writers"] == ["robot"] else "human")
        )
        assert r["typed_text"] == ("" if answer is None else answer.strip())
        if trial["is_attention_check"]:
            assert (r["attention_pass"], r["correct"]) == ("true", "false")
        else:
            assert bool_(r["correct"]) == (
                answer is not None and answer.strip().lower() == trial["word"]
            )
    assert [r["writer"] for r in rows if r["is_attention_check"] == "false"].count("robot") == 3
    read = load_responses(download.value.path())  # what prg-study analyze reads
    assert read.kinds == ["readability"] and len(read.frame) == len(rows)


def pad_on_page(page) -> tuple[dict, float]:
    """The pad's bounding box on the page, and page pixels per canvas CSS pixel."""
    box = page.locator("#pad").bounding_box()
    return box, box["width"] / page.evaluate("PRGCapture.config.canvas_width")


def draw(page, points) -> None:
    """One pen stroke through ``points`` (canvas CSS pixels, y down) with the mouse."""
    box, scale = pad_on_page(page)
    (x, y), *rest = points
    page.mouse.move(box["x"] + x * scale, box["y"] + y * scale)
    page.mouse.down()
    for x, y in rest:
        page.mouse.move(box["x"] + x * scale, box["y"] + y * scale)
    page.mouse.up()


def draw_at_times(page, points, interval_s: float) -> None:
    """One pen stroke through ``points`` (canvas CSS pixels, y down), an event every
    ``interval_s`` seconds of the pen's own clock.

    The events carry their times (Chrome DevTools ``Input.dispatchMouseEvent``'s ``timestamp``,
    which becomes the event's ``timeStamp``), as a tablet's do, so the recorded times are the
    pen's and not when a loaded test machine got round to sending each event."""
    box, scale = pad_on_page(page)
    devtools = page.context.new_cdp_session(page)
    start = time.time()
    events = [("mousePressed", points[0], 0)]
    events += [("mouseMoved", point, i) for i, point in enumerate(points) if i > 0]
    events += [("mouseReleased", points[-1], len(points) - 1)]
    for kind, (x, y), i in events:
        devtools.send(
            "Input.dispatchMouseEvent",
            {
                "type": kind,
                "x": box["x"] + x * scale,
                "y": box["y"] + y * scale,
                "button": "left",
                "buttons": 0 if kind == "mouseReleased" else 1,
                "clickCount": 1,
                "timestamp": start + i * interval_s,
            },
        )
    devtools.detach()


def loops(n: int = 36) -> list[tuple[float, float]]:
    """A loopy word-like path on the canvas (CSS pixels), 70 px high."""
    return [
        (60 + 18 * (i / 5) + 25 * math.sin(i / 5 * 6), 150 - 35 * math.cos(i / 5 * 6))
        for i in range(n)
    ]


def height(points) -> float:
    return max(p[1] for p in points) - min(p[1] for p in points)


def size(points) -> float:
    """The larger side of the bounding box."""
    return max(max(p[d] for p in points) - min(p[d] for p in points) for d in (0, 1))


def test_my_style_records_letters_into_a_style_file_prg_write_reads(
    page, tmp_path, samples, untrained_muse_checkpoint
):
    """The capture page's "my style" flow: single letters, one stroke each, downloaded as a
    style file that :func:`prg.pipeline.hands.read_style` and ``Writer(style=...)`` take."""
    from prg import Writer
    from prg.alphabet import char_to_label
    from prg.pipeline.hands import read_style

    folder = build(tmp_path / "b", "turing", "attention_checks=[]", robot=samples["robot"])
    page.goto((folder / "capture" / "index.html").as_uri() + "?writer=me&style=aeb")
    assert "My style" in page.text_content("h1")
    page.click("#begin")
    with page.expect_download() as download:
        for k, letter in enumerate("aeb"):
            assert page.text_content("#word") == letter
            assert page.text_content("#next") == ("Next letter" if k < 2 else "Finish")
            write_word(page, k)
            page.click("#next")
    assert download.value.suggested_filename.startswith("style_me_")
    path = tmp_path / "style.json"
    path.write_text(Path(download.value.path()).read_text())
    doc = json.loads(path.read_text())
    assert doc["purpose"] == "style" and doc["delayed_strokes"] is False
    traj, labels = read_style(path)
    assert traj.shape == (3, 200) and [int(y) for y in labels] == [char_to_label(c) for c in "aeb"]
    word = Writer.from_checkpoint(untrained_muse_checkpoint, style=path).write(text="bead")
    assert word.text == "bead" and word.letters.shape == (4, 100, 2)


def test_captured_human_strokes_fit_a_dmp_that_starts_and_ends_moving(page, tmp_path, samples):
    """A writer's words from the capture page, at their recorded times, go through the DMP fit
    of human demonstrations (prg.pipeline.dmp: ``uniform_in_time``, then ``fit_dmp(...,
    velocities="demonstrated")``): the rollout reproduces each stroke, including its first
    movement, which a DMP fitted at rest misses."""
    from prg.pipeline.dmp import fit_dmp, rollout, uniform_in_time

    folder = build(
        tmp_path / "b",
        "turing",
        "words=[cat, dog]",
        "attention_checks=[]",
        "delayed_strokes=false",
        robot=samples["robot"],
    )
    page.goto((folder / "capture" / "index.html").as_uri() + "?writer=w7")
    page.click("#begin")
    with page.expect_download() as download:
        for k in range(2):
            # a pen already moving when it touches down: fast straight into the loops, at 100 Hz
            # (a real writer's tablet rate)
            entry = [(40 + 6 * i, 150) for i in range(6)]
            draw_at_times(page, [(x, y + k) for x, y in entry + loops(60)[2:]], interval_s=0.010)
            page.click("#next")
    doc = json.loads(Path(download.value.path()).read_text())
    for sample in doc["samples"]:
        (stroke,) = sample["strokes"]
        raw = np.array([p[:2] for p in stroke])
        seconds = np.array([p[2] for p in stroke]) / 1000.0
        # the pen's clock, recorded (Chromium moves a time by up to about 0.5 ms)
        assert np.allclose(np.diff(seconds), 0.010, atol=1e-3)
        uniform, duration = uniform_in_time(raw, seconds, n_samples=4 * len(raw))
        size = np.ptp(uniform, axis=0).max()
        errors = {}
        for velocities in ("rest", "demonstrated"):
            dmp = fit_dmp(
                # one basis function per pen sample: a mouse path turns at every sample
                uniform,
                tau=duration,
                n_basis=len(raw),
                velocities=velocities,
            )
            errors[velocities] = np.linalg.norm(rollout(dmp) - uniform, axis=1)
        first = slice(0, len(uniform) // 20)  # the first movement, the straight entry
        assert errors["demonstrated"][first].max() < 0.5 * errors["rest"][first].max()
        assert np.sqrt(np.mean(errors["demonstrated"] ** 2)) < 0.01 * size, sample["word"]


def test_capture_json_round_trips_into_a_runnable_study(page, tmp_path, samples):
    unready = build(
        tmp_path / "first",
        "turing",
        "words=[cat, dog]",
        "attention_checks=[]",
        "delayed_strokes=false",  # the paper's single stroke
        robot=samples["robot"],
    )
    assert json.loads((unready / "manifest.json").read_text())["ready"] is False
    recordings = tmp_path / "recordings"
    recordings.mkdir()
    for n in range(3):
        doc = capture(page, unready, f"w{n}", restart_on=1 if n == 0 else None)
        (recordings / f"w{n}.json").write_text(json.dumps(doc))

    doc = json.loads((recordings / "w0.json").read_text())
    assert (doc["schema"], doc["version"], doc["writer_id"]) == ("prg.handwriting_capture", 1, "w0")
    assert doc["canvas"]["y_down"] is True and doc["canvas"]["units"] == "css_px"
    assert doc["delayed_strokes"] is False
    assert [s["word"] for s in doc["samples"]] == ["cat", "dog"]
    for s in doc["samples"]:
        (stroke,) = s["strokes"]  # one continuous stroke
        assert len(stroke) >= 15 and all(len(p) == 4 for p in stroke)
        times = [p[2] for p in stroke]
        assert times[0] == 0 and times == sorted(times) and s["duration_ms"] == times[-1]
        assert all(
            0 <= p[0] <= doc["canvas"]["width"] and 0 <= p[1] <= doc["canvas"]["height"]
            for p in stroke
        )
        assert s["pointer_type"] == "mouse" and s["lifted"] is False and s["delayed"] == []
    assert [s["restarts"] for s in doc["samples"]] == [0, 1]
    assert len(doc["samples"][1]["strokes"][0]) < 25  # only the attempt after the lift is kept

    ready = build(
        tmp_path / "second",
        "turing",
        "words=[cat, dog]",
        "human_writers=3",
        "foils=2",
        "participants=3",
        "completion.redirect_delay_ms=0",
        "attention_checks=[]",
        "delayed_strokes=false",
        robot=samples["robot"],
        human=recordings,
    )
    manifest = json.loads((ready / "manifest.json").read_text())
    assert manifest["ready"] is True
    assert manifest["human_writers"] == {"cat": ["w0", "w1", "w2"], "dog": ["w0", "w1", "w2"]}
    row = start(page, (ready / "index.html").as_uri() + "?PROLIFIC_PID=rt1")
    assert page.locator(".option").count() == 3  # the robot and two foils
    with page.expect_download() as download:
        for trial in row["trials"]:
            page.click(f"[data-option='{trial['robot_index'] + 1}']")
            page.click("[data-confidence='5']")
            page.click("#next")
    page.wait_for_url(PROLIFIC)
    _, rows = read_csv(Path(download.value.path()).read_text())
    assert [r["chose_robot"] for r in rows] == ["true", "true"]


@pytest.mark.parametrize("delayed", [False, True])
def test_capture_page_can_flag_lifts_instead_of_restarting(page, tmp_path, samples, delayed):
    folder = build(
        tmp_path / "b",
        "turing",
        "words=[cat]",
        "attention_checks=[]",
        "capture.on_lift=flag",
        f"delayed_strokes={str(delayed).lower()}",
        robot=samples["robot"],
    )
    page.goto((folder / "capture" / "index.html").as_uri())
    assert page.is_disabled("#begin")
    page.fill("#writer-id", "robot")
    assert page.is_disabled("#begin")  # reserved for the robot's samples
    page.fill("#writer-id", "w9")
    page.click("#begin")
    with page.expect_download() as download:
        write_word(page, 0, lift=True)
        assert "marked" in page.text_content("#message")
        page.click("#next")
    doc = json.loads(Path(download.value.path()).read_text())
    (sample,) = doc["samples"]
    # with delayed strokes on, the second half of the word is too big for a dot or a bar
    assert sample["lifted"] is True and len(sample["strokes"]) == 2 and sample["delayed"] == []
    assert sample["strokes"][1][0][2] > sample["strokes"][0][-1][2]  # one clock per word
    recordings = tmp_path / "rec"
    recordings.mkdir()
    (recordings / "w9.json").write_text(json.dumps(doc))
    from studies.stimuli import load_human_samples

    assert load_human_samples([recordings], ["cat"]).writers() == {"cat": []}
    assert load_human_samples([recordings], ["cat"], accept_lifted=True).writers() == {
        "cat": ["w9"]
    }


def test_capture_page_keeps_dots_and_bars_after_the_word_and_clears_a_lift(page, tmp_path, samples):
    folder = build(
        tmp_path / "b", "turing", "words=[ink, cat]", "attention_checks=[]", robot=samples["robot"]
    )  # delayed strokes on, lifts restart the word: the shipped study
    page.goto((folder / "capture" / "index.html").as_uri() + "?writer=w5")
    assert "dot the i's and j's and cross the t's and f's" in page.text_content("#intro-text")
    fraction = page.evaluate("PRGCapture.config.delayed_max_size")
    word = loops()
    limit = fraction * height(word)  # the largest dot or bar the page keeps
    top = min(y for _, y in word)
    dot = [(120, top - 25), (120 + 0.1 * limit, top - 25)]
    bar = [(180 - 0.4 * limit, top + 10), (180 + 0.4 * limit, top + 10)]
    big = [(300, 150), (300 + 1.4 * limit, 150 - 1.2 * limit)]  # the rest of a word: a lift
    page.click("#begin")
    assert "dot the i's" in page.text_content("#task")
    with page.expect_download() as download:
        assert page.text_content("#word") == "ink"
        for stroke in (word, dot, bar):
            draw(page, stroke)
        assert page.text_content("#message") == ""
        page.click("#next")
        assert page.text_content("#word") == "cat"
        draw(page, word)
        draw(page, big)
        assert "word was cleared" in page.text_content("#message")
        assert page.is_disabled("#next")  # nothing left to keep
        draw(page, word)
        draw(page, bar)
        page.click("#next")
    doc = json.loads(Path(download.value.path()).read_text())
    assert doc["delayed_strokes"] is True and doc["delayed_max_size"] == fraction
    ink, cat = doc["samples"]
    assert (len(ink["strokes"]), ink["delayed"], ink["lifted"], ink["restarts"]) == (
        3,
        [1, 2],
        False,
        0,
    )
    assert (len(cat["strokes"]), cat["delayed"], cat["lifted"], cat["restarts"]) == (
        2,
        [1],
        False,
        1,
    )
    for sample in (ink, cat):  # the page's rule, checked on what it recorded
        first = sample["strokes"][0]
        assert len(first) >= 30 and height(first) == pytest.approx(height(word), abs=2)
        for k in sample["delayed"]:
            assert size(sample["strokes"][k]) <= fraction * height(first)
    assert cat["strokes"][1][0][2] > cat["strokes"][0][-1][2]  # the bar after the word

    recordings = tmp_path / "rec"
    recordings.mkdir()
    (recordings / "w5.json").write_text(json.dumps(doc))
    from studies.stimuli import load_human_samples

    found = load_human_samples([recordings], ["ink", "cat"])
    assert found.writers() == {"ink": ["w5"], "cat": ["w5"]} and found.notes == []
    assert [len(found.by_word[w]["w5"].strokes) for w in ("ink", "cat")] == [3, 2]
    assert found.by_word["ink"]["w5"].delayed == (1, 2)


def test_capture_page_flags_a_lift_after_the_dots(page, tmp_path, samples):
    folder = build(
        tmp_path / "b",
        "turing",
        "words=[ink]",
        "attention_checks=[]",
        "capture.on_lift=flag",
        robot=samples["robot"],
    )
    page.goto((folder / "capture" / "index.html").as_uri() + "?writer=w6")
    page.click("#begin")
    word = loops()
    limit = page.evaluate("PRGCapture.config.delayed_max_size") * height(word)
    with page.expect_download() as download:
        draw(page, word)
        draw(page, [(120, 60), (120 + 0.5 * limit, 60)])  # a bar
        assert page.text_content("#message") == ""
        draw(page, [(300, 150), (300 + 2.4 * limit, 150)])  # just too long for a bar
        assert "marked" in page.text_content("#message")
        page.click("#next")
    (sample,) = json.loads(Path(download.value.path()).read_text())["samples"]
    assert (len(sample["strokes"]), sample["delayed"], sample["lifted"]) == (3, [1], True)
    recordings = tmp_path / "rec"
    recordings.mkdir()
    (recordings / "w6.json").write_text(
        json.dumps(json.loads(Path(download.value.path()).read_text()))
    )
    from studies.stimuli import load_human_samples

    found = load_human_samples([recordings], ["ink"])
    assert found.writers() == {"ink": []} and "w6/ink was written with a pen lift" in found.notes[0]


def test_without_human_samples_the_build_says_what_is_missing(page, tmp_path, samples, capsys):
    out = build(tmp_path / "b", "readability", robot=samples["robot"])
    err = capsys.readouterr().err
    assert "readability: NOT READY" in err and "capture/" in err
    assert "missing: no human samples were given" in err
    assert len(list((out / "stim").iterdir())) == len(WORDS)  # the robot's words
    assert (out / "capture" / "index.html").is_file()
    assert json.loads((out / "trials.json").read_text()) == {"rows": []}
    page.goto((out / "index.html").as_uri())
    assert "not ready" in page.text_content("#not-ready")
    assert "human writers" in page.text_content("main ul")


def test_a_pilot_build_runs_with_stand_ins_and_is_marked_pilot_everywhere(
    page, tmp_path, samples, capsys, monkeypatch
):
    monkeypatch.chdir(tmp_path)  # no prepared dataset here: the robot's words make the stand-ins
    posted = []
    page.route(COLLECT, lambda route: (posted.append(route.request), route.fulfill(body="ok")))
    out = tmp_path / "pilot"
    args = ["build", str(REPO / "conf/study/readability.yaml"), "--out", str(out), "--pilot"]
    args += ["--robot", str(samples["robot"]), "--set", "words=[cat, dog]", "-q"]
    args += ["--set", f"save.post_url={COLLECT}", "--set", "completion.redirect_delay_ms=1500"]
    assert main([*args, "--set", "participants=2", "--set", "attention_checks=[]"]) == 0
    assert "readability: PILOT build" in capsys.readouterr().err
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["ready"] is manifest["pilot"] is True
    assert manifest["app_version"].endswith("-pilot")
    assert manifest["human_writers"]["cat"] == [f"pilot{k:02d}" for k in range(1, 11)]
    assert manifest["stand_ins"] == 2 * 10

    def marked() -> None:  # the screen shown now says PILOT
        assert page.title().startswith("PILOT")
        assert page.is_visible("#pilot-banner")
        assert "PILOT" in page.text_content("#pilot-banner")

    page.goto((out / "index.html").as_uri() + "?row=1")
    marked()  # consent
    page.check("#consent-agree")
    page.click("#consent-continue")
    marked()  # instructions
    page.click("#start:not([disabled])")
    row = page.evaluate("PRGStudy.state.row")
    with page.expect_download() as download:
        for trial in row["trials"]:
            marked()
            page.fill("#answer", trial["word"])
            page.click("#next")
    marked()  # the end
    code = page.text_content("#completion-code")
    assert code.startswith("PILOT-") and code != "PILOT-"
    page.wait_for_url(PROLIFIC)
    assert parse_qs(urlparse(page.url).query) == {"cc": [code]}
    assert posted == []  # a pilot never sends its answers to the study's collector
    assert download.value.suggested_filename.startswith("PILOT_readability_")
    text = Path(download.value.path()).read_text()
    _, rows = read_csv(text)
    assert [r["correct"] for r in rows] == ["true", "true"]
    assert {r["app_version"] for r in rows} == {manifest["app_version"]}

    page.goto((out / "capture" / "index.html").as_uri())  # the capture page too
    marked()

    # the analysis never takes pilot rows together with a study's
    columns, pilot_rows = read_csv(text)
    study_rows = [
        dict(r, participant_id="p1", app_version=r["app_version"].removesuffix("-pilot"))
        for r in pilot_rows
    ]
    mixed = tmp_path / "mixed.csv"
    with mixed.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, columns)
        writer.writeheader()
        writer.writerows(pilot_rows + study_rows)
    with pytest.raises(ResponseFileError) as err:
        load_responses(mixed)
    assert (
        "mixes 2 rows from the study's page (first on line 4) and 2 rows from a pilot build "
        "(first on line 2): never analysed together" in str(err.value)
    )
    assert load_responses(download.value.path()).origin == "pilot"


def test_the_not_ready_page_points_at_the_pilot_copy_beside_it(
    page, tmp_path, samples, capsys, monkeypatch
):
    monkeypatch.chdir(tmp_path)  # the default folders: studies/readability/build and .../pilot
    args = ["build", str(REPO / "conf/study/readability.yaml"), "--robot", str(samples["robot"])]
    args += ["--set", "words=[cat, dog]", "--set", "participants=2", "-q"]
    args += ["--set", "attention_checks=[]"]
    assert main(args) == 0
    err = capsys.readouterr().err
    assert "readability: NOT READY" in err
    assert (
        f"to try the pages now: prg-study build {REPO / 'conf/study/readability.yaml'} --pilot"
        in err
    )
    real = tmp_path / "studies" / "readability" / "build"
    before = {p: p.read_bytes() for p in real.rglob("*") if p.is_file()}
    assert main([*args, "--pilot"]) == 0
    assert "readability: PILOT build" in capsys.readouterr().err
    pilot = tmp_path / "studies" / "readability" / "pilot"
    assert json.loads((pilot / "manifest.json").read_text())["pilot"] is True
    assert main([*args, "--pilot", "--out", str(real)]) == 2  # never over the study's build
    assert "holds a study's own build" in capsys.readouterr().err
    assert {p: p.read_bytes() for p in real.rglob("*") if p.is_file()} == before  # untouched

    page.goto((real / "index.html").as_uri())
    assert "not ready" in page.text_content("#not-ready")
    assert page.locator("#pilot-banner").count() == 0  # the real page is not a pilot
    assert "PILOT copy" in page.text_content("#pilot-hint")
    page.click("#pilot-copy")
    assert page.url == (pilot / "index.html").as_uri()
    assert "PILOT" in page.text_content("#pilot-banner")
    # it runs: the page's script shows the consent step once loaded (wait for it: under a full
    # parallel test run, an immediate check raced the script)
    page.wait_for_selector("#consent-agree", state="visible", timeout=10_000)
    assert page.is_visible("#consent-agree")


def test_the_module_runs_as_a_command(tmp_path):
    result = subprocess.run(
        [sys.executable, "-m", "studies.cli", "build", "missing.yaml"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=120,
    )
    assert result.returncode == 2
    assert (
        result.stderr
        == "prg-study: error: missing.yaml: no such study file (e.g. conf/study/turing.yaml)\n"
    )


# ---------------------------------------------------------------------------- layout
SCREENS = {"laptop": (1280, 800), "phone": (390, 844)}


@pytest.fixture(scope="module")
def pilot_builds(tmp_path_factory) -> dict[str, Path]:
    """Pilot builds of both shipped studies as they are (10 words, 5 samples a Turing trial, an
    attention check): the PILOT banner takes room on every screen."""
    from studies.design_config import load_study

    root = tmp_path_factory.mktemp("pilots")
    robot = robot_dir(root / "robot", load_study(REPO / TURING).words)
    out = {}
    for study in ("turing", "readability"):
        out[study] = root / study
        args = ["build", str(REPO / f"conf/study/{study}.yaml"), "--pilot", "-q"]
        assert main([*args, "--robot", str(robot), "--out", str(out[study])]) == 0
    return out


def fit(page) -> dict:
    """The document's scroll size, the window's size, and each sample's box and drawn size."""
    return page.evaluate(
        """() => ({
        scroll: [document.documentElement.scrollWidth, document.documentElement.scrollHeight],
        window: [window.innerWidth, window.innerHeight],
        images: Array.from(document.querySelectorAll('main img')).map(img => {
            const box = img.getBoundingClientRect();
            const scale = Math.min(box.width / img.naturalWidth, box.height / img.naturalHeight);
            return {left: box.left, right: box.right, top: box.top, bottom: box.bottom,
                    drawn: [img.naturalWidth * scale, img.naturalHeight * scale]};
        }),
    })"""
    )


@pytest.mark.parametrize("screen", SCREENS)
@pytest.mark.parametrize("study", ["turing", "readability"])
def test_every_trial_fits_a_laptop_screen_and_a_phones_width(chromium, pilot_builds, study, screen):
    width, height = SCREENS[screen]
    context = chromium.new_context(viewport={"width": width, "height": height})
    page = context.new_page()
    row = start(page, (pilot_builds[study] / "index.html").as_uri() + "?row=3")
    assert any(t["is_attention_check"] for t in row["trials"])  # the longest screen is measured
    for i in range(len(row["trials"])):
        m = fit(page)
        where = f"{screen} {width}x{height}, trial {i + 1}"
        assert m["window"] == [width, height]
        assert m["scroll"][0] <= width, f"{where}: the page scrolls sideways ({m['scroll']})"
        if screen == "laptop":
            assert m["scroll"][1] <= height, f"{where}: the page scrolls down ({m['scroll']})"
        samples = m["images"]
        assert len(samples) == (5 if study == "turing" else 1)
        for box in samples:
            assert box["left"] >= 0 and box["right"] <= width, f"{where}: a sample overflows"
            if screen == "laptop":  # whole on the screen, and big enough to read
                assert box["top"] >= 0 and box["bottom"] <= height, f"{where}: a sample is cut"
                assert box["drawn"][1] >= 100, f"{where}: a sample drawn {box['drawn']}"
            else:
                assert box["drawn"][0] >= 250, f"{where}: a sample drawn {box['drawn']}"
        if study == "turing":
            page.click("[data-option='1']")
            page.click("[data-confidence='3']")
            page.click("#next")
        else:
            page.fill("#answer", "blue")
            page.press("#answer", "Enter")
    assert page.is_visible("#completion-code")
    context.close()
