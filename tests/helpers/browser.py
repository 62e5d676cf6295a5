"""Helpers for the study tests: a headless Debian chromium driven by Playwright, a loopback
static server, and synthetic robot and human handwriting samples.

The browser is the system's ``chromium`` (``apt-get install chromium``; ``PRG_CHROMIUM``
overrides the path) driven by the ``playwright`` package (``pip install playwright`` or the
``browser`` extra); Playwright's own browser downloads are never used, so the tests run offline.
"""

from __future__ import annotations

import csv
import functools
import http.server
import io
import json
import os
import shutil
import threading
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from prg.pipeline.word import WordTrajectory


def chromium_path() -> str:
    """The chromium executable: ``$PRG_CHROMIUM``, else ``chromium`` on the PATH."""
    path = os.environ.get("PRG_CHROMIUM") or shutil.which("chromium") or "/usr/bin/chromium"
    if not Path(path).exists():
        raise RuntimeError(
            f"no chromium at {path}: install it with `apt-get install chromium` (make system) "
            "or set PRG_CHROMIUM to a Chromium executable"
        )
    return path


@contextmanager
def browser() -> Iterator:
    """A headless chromium (Playwright ``Browser``), closed on exit."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError as err:  # pragma: no cover - depends on the environment
        raise RuntimeError(
            "the browser tests need playwright: pip install -e '.[browser]' (no browser "
            "download is needed: they use the Debian chromium)"
        ) from err
    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=chromium_path(), headless=True)
        try:
            yield b
        finally:
            b.close()


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format, *args):
        pass


@contextmanager
def serve(folder: Path) -> Iterator[str]:
    """Serve ``folder`` on 127.0.0.1 (a free port) in a thread; yields the base URL."""
    handler = functools.partial(_Quiet, directory=str(folder))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()
        thread.join(5)


def wobbly_word(word: str, rng: np.random.Generator, n_per_letter: int = 30) -> np.ndarray:
    """One continuous cursive-like stroke for ``word`` (loops along a baseline), y up, cm."""
    n = n_per_letter * len(word)
    t = np.linspace(0, len(word), n)
    x = t * rng.uniform(0.8, 1.1) + 0.3 * np.sin(2 * np.pi * t)
    y = 0.25 + 0.25 * np.cos(2 * np.pi * t + rng.uniform(0, 1)) + rng.normal(0, 0.01, n)
    return np.column_stack([x, y])


def robot_dir(folder: Path, words: Sequence[str], seed: int = 0) -> Path:
    """``<folder>/<word>.json`` word trajectories (one letter segment per character)."""
    rng = np.random.default_rng(seed)
    folder.mkdir(parents=True, exist_ok=True)
    for word in words:
        pts = wobbly_word(word, rng)
        seg = np.minimum(np.arange(len(pts)) * len(word) // len(pts), len(word) - 1)
        WordTrajectory(pts, seg, ["letter"] * len(word), word).to_json(folder / f"{word}.json")
    return folder


def capture_document(writer_id: str, words: Sequence[str], seed: int = 0) -> dict:
    """A capture-page document (schema ``prg.handwriting_capture``) with synthetic strokes."""
    rng = np.random.default_rng(seed)
    samples = []
    for word in words:
        pts = wobbly_word(word, rng) * [80, -80] + [60, 200]  # CSS pixels, y down
        t = np.cumsum(rng.uniform(8, 17, len(pts)))
        stroke = [[round(x, 2), round(y, 2), round(float(s), 1), 0.5] for (x, y), s in zip(pts, t)]
        samples.append(
            {"word": word, "strokes": [stroke], "lifted": False, "restarts": 0, "skipped": False}
        )
    return {
        "schema": "prg.handwriting_capture",
        "version": 1,
        "writer_id": writer_id,
        "canvas": {"width": 900, "height": 300, "units": "css_px", "y_down": True},
        "samples": samples,
    }


def human_dir(folder: Path, words: Sequence[str], writers: int, seed: int = 0) -> Path:
    """One capture file per writer ``w01``, ``w02`` ... in ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    for k in range(writers):
        doc = capture_document(f"w{k + 1:02d}", words, seed=seed * 1000 + k)
        (folder / f"capture_w{k + 1:02d}.json").write_text(json.dumps(doc))
    return folder


def read_csv(text: str) -> tuple[list[str], list[dict[str, str]]]:
    """Header and rows of a CSV text."""
    reader = csv.DictReader(io.StringIO(text))
    rows = list(reader)
    return list(reader.fieldnames or []), rows
