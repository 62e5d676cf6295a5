"""The documentation: the site builds offline with warnings as errors, the tutorial and the
public API's Examples run as written, and the README's front door points at pages that exist."""

from __future__ import annotations

import doctest
import importlib
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
DOCS = REPO / "docs"
OPTIONS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
#: pages whose code blocks are doctests a reader can run from the checkout's root
TUTORIALS = ["tutorial.md"]
#: modules whose docstrings carry Examples on the public API
DOCTESTED = [
    "prg.writer",
    "prg.pipeline.dmp.regression",
    "prg.pipeline.dmp.integration",
    "prg.pipeline.joins",
    "prg.pipeline.timing",
    "studies.analysis.stats.proportions",
    "studies.analysis.stats.parametric",
]
#: one page per topic (the README's documentation table links to each)
TOPICS = {
    "tutorial", "data", "training", "evaluation", "writing", "python", "speech", "dmp", "robot",
    "export", "recordings", "studies", "tracking", "scaling", "commands", "results",
    "benchmarks", "api", "changelog", "development",
}  # fmt: skip


@pytest.fixture
def project(tmp_path, untrained_muse_checkpoint, monkeypatch) -> Path:
    """A project folder with ``models/muse/model.ckpt`` (an untrained MUSE: plumbing, the
    printed shapes and names, not handwriting), as a reader has after ``make demo``."""
    (tmp_path / "models" / "muse").mkdir(parents=True)
    shutil.copyfile(untrained_muse_checkpoint, tmp_path / "models" / "muse" / "model.ckpt")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("PRG_ROOT", str(tmp_path))
    return tmp_path


def test_the_site_builds_offline_with_warnings_as_errors(tmp_path):
    out = tmp_path / "html"
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", DOCS, out],
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert proc.returncode == 0, proc.stderr[-4000:]
    assert {p.stem for p in out.glob("*.html")} >= TOPICS
    writer_page = (out / "generated" / "prg.writer.html").read_text()
    assert "prg.writer.Writer" in writer_page and "Examples" in writer_page
    assert (out / "generated" / "studies.analysis.stats.proportions.html").is_file()


@pytest.mark.parametrize("page", TUTORIALS)
def test_the_tutorial_runs_as_written(page, project):
    result = doctest.testfile(str(DOCS / page), module_relative=False, optionflags=OPTIONS)
    assert result.attempted > 10 and result.failed == 0


@pytest.mark.parametrize("name", DOCTESTED)
def test_the_public_api_examples_run(name, project):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=OPTIONS)
    assert result.attempted > 0 and result.failed == 0
    assert not (project / "outputs").exists()  # an example writes nothing it does not show


def test_the_readme_is_a_front_door_linking_pages_that_exist():
    readme = (REPO / "README.md").read_text()
    assert len(readme.splitlines()) <= 300
    links = set(re.findall(r"\]\((docs/[^)#]+)\)", readme))
    assert {f"docs/{topic}.md" for topic in TOPICS - {"tutorial"}} <= links
    missing = sorted(link for link in links if not (REPO / link).is_file())
    assert not missing, f"README links to missing files: {missing}"
    for figure in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", readme):
        assert (REPO / figure).is_file(), figure
