"""Helpers shared by the tests that were split out of tests/test_study_web.py."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from studies.cli import main
from tests.helpers.browser import browser, human_dir, robot_dir

REPO = Path(__file__).resolve().parents[2]


WORDS = ["cat", "dog", "sun", "egg", "ink", "owl"]


PROLIFIC = "https://app.prolific.com/**"


@pytest.fixture(scope="module")
def chromium():
    with browser() as b:
        yield b


@pytest.fixture
def page(chromium):
    context = chromium.new_context(accept_downloads=True)
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda err: errors.append(str(err)))
    page.route(PROLIFIC, lambda r: r.fulfill(status=200, content_type="text/html", body="done"))
    yield page
    context.close()
    assert errors == [], f"JavaScript errors: {errors}"


@pytest.fixture(scope="module")
def samples(tmp_path_factory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("samples")
    return {"robot": robot_dir(root / "robot", WORDS), "human": human_dir(root / "human", WORDS, 5)}


def build(
    out: Path, study: str, *settings: str, robot: Path | None = None, human: Path | None = None
) -> Path:
    """``prg-study build`` of a conf/study file for :data:`WORDS` (5 human writers a word)."""
    args = ["build", str(REPO / f"conf/study/{study}.yaml"), "--out", str(out), "-q"]
    args += ["--robot", str(robot)] if robot else []
    args += ["--human", str(human)] if human else []
    for s in (f"words=[{', '.join(WORDS)}]", "human_writers=5", *settings):
        args += ["--set", s]
    assert main(args) == 0
    return out


# ---------------------------------------------------------------------------- the capture page
def write_word(page, k: int, lift: bool = False) -> None:
    """Draw a loopy stroke on the pad with the mouse (optionally lifting the button midway)."""
    box = page.locator("#pad").bounding_box()
    x0, y0 = box["x"] + 60, box["y"] + 190
    page.mouse.move(x0, y0)
    page.mouse.down()
    for i in range(1, 36):
        t = i / 5
        page.mouse.move(x0 + 18 * t + 25 * math.sin(t * 6 + k), y0 - 40 - 35 * math.cos(t * 6 + k))
        if lift and i == 18:
            page.mouse.up()
            page.mouse.down()
    page.mouse.up()


def capture(page, folder: Path, writer: str, restart_on: int | None = None) -> dict:
    """Record every word of the capture page as ``writer``; returns the saved JSON."""
    page.goto((folder / "capture" / "index.html").as_uri() + f"?writer={writer}")
    page.click("#begin")
    words = page.evaluate("PRGCapture.config.words")
    with page.expect_download() as download:
        for k, word in enumerate(words):
            assert page.text_content("#word") == word
            assert page.is_disabled("#next")
            write_word(page, k, lift=k == restart_on)
            if k == restart_on:
                assert "write it again" in page.text_content("#message")
            page.click("#next")
    assert download.value.suggested_filename.startswith(f"capture_{writer}_")
    return json.loads(Path(download.value.path()).read_text())


TURING = "conf/study/turing.yaml"
