"""The study's web pages: the assets each page loads, its ``index.html`` from one skeleton
(``web/page.html``), the page settings (``config.js``), the PILOT banner and the build's README.
Pure functions of a :class:`~studies.design_config.StudySettings`; :mod:`studies.bundle` writes
them into a build.
"""

from __future__ import annotations

import html
import json
import string
from importlib import resources
from pathlib import Path

from studies.design_config import StudySettings

try:
    from studies.analysis.schema import PILOT_SUFFIX, STUDY_COLUMNS
except ImportError:  # the analysis package is not there: the columns it documents
    PILOT_SUFFIX = "-pilot"
    _HEAD = ("participant_id", "session_id", "study", "list_id", "trial", "word")
    _TAIL = ("rt_ms", "is_attention_check", "attention_pass", "timestamp", "app_version", "seed")
    STUDY_COLUMNS = {
        "turing": (*_HEAD, "robot_index", "chosen_index", "chose_robot", "confidence", *_TAIL),
        "readability": (*_HEAD, "writer", "typed_text", "correct", *_TAIL),
    }

#: Recorded after the analysis columns: Prolific's STUDY_ID (the analysis ignores it).
EXTRA_COLUMNS: tuple[str, ...] = ("study_id",)
#: What both pages load first (each page's folder gets its copy: capture/ is hosted on its own too).
COMMON_ASSETS = {"common.js": "common.js", "common.css": "common.css"}
STUDY_ASSETS = {**COMMON_ASSETS, "study.js": "study.js", "study.css": "study.css"}
CAPTURE_ASSETS = {**COMMON_ASSETS, "capture.js": "capture.js", "capture.css": "capture.css"}
#: The two pages' ``index.html``, from one skeleton (``web/page.html``): what differs.
PAGES = {
    "study": {
        "title": "Handwriting study",
        "viewport": "width=device-width, initial-scale=1",
        "noun": "study",
        "data": ("config.js", "trials.js"),
    },
    "capture": {
        "title": "Handwriting recording",
        "viewport": "width=device-width, initial-scale=1, user-scalable=no",
        "noun": "page",
        "data": ("config.js",),
    },
}


def response_columns(kind: str) -> tuple[str, ...]:
    """The CSV columns the page writes for a study kind, in order."""
    return (*STUDY_COLUMNS[kind], *EXTRA_COLUMNS)


def pilot_banner(stand_ins: int, page: str = "study") -> str:
    """What the PILOT banner says after "PILOT \u2014" on ``page`` (``study`` or ``capture``)
    of a pilot build."""
    if page == "capture":
        return (
            "this capture page belongs to a pilot build: record the study's writers with the "
            "capture page of the study's own build."
        )
    what = (
        "the human samples here are stand-ins made from the robot's writing"
        if stand_ins
        else "a trial run of the study pages"
    )
    return f"{what}. For trying the pages only: do not collect data."


def web_asset(name: str) -> bytes:
    """A file of ``studies/web/``."""
    return resources.files("studies").joinpath("web", name).read_bytes()


def page_html(page: str, banner: str | None = None) -> bytes:
    """The ``index.html`` of ``page`` (``study`` or ``capture``): the skeleton with its title,
    viewport, stylesheet and scripts (the data scripts first, then ``common.js``, then its own);
    with a ``banner`` (a pilot build's: what follows "PILOT —"), the banner above every screen
    and "PILOT" in the title."""
    fields = PAGES[page]
    data = "".join(f'<script src="{name}"></script>\n' for name in fields["data"])
    skeleton = string.Template(web_asset("page.html").decode("utf-8"))
    top = (
        '<div class="pilot-banner" id="pilot-banner" role="note"><strong class="pilot-tag">'
        f"PILOT</strong> \u2014 {html.escape(banner)}</div>\n"
        if banner
        else ""
    )
    return skeleton.substitute(
        page=page,
        banner=top,
        title=("PILOT \u2014 " if banner else "") + fields["title"],
        viewport=fields["viewport"],
        noun=fields["noun"],
        data=data,
    ).encode("utf-8")


def js_assignment(variable: str, value) -> str:
    """``window.<variable> = <JSON>;`` safe inside an HTML page (no ``</script>``)."""
    text = json.dumps(value, indent=1, ensure_ascii=False, sort_keys=True).replace("</", "<\\/")
    return f"window.{variable} = {text};\n"


def page_config(
    config: StudySettings,
    app_version: str,
    ready: bool,
    missing: list[str],
    pilot: bool,
    pilot_copy: str | None,
) -> dict:
    """The page settings of ``config.js``/``config.json`` (a pilot's code starts with PILOT-)."""
    code = config.completion["code"]
    url = config.completion["url"]
    if pilot:  # a pilot's answers and code never pass for the study's
        code = f"PILOT-{code}"
    return {
        "name": config.name,
        "kind": config.kind,
        "title": config.page["title"],
        "consent": config.page["consent"],
        "instructions": config.page["instructions"],
        "confidence_labels": config.page["confidence_labels"],
        "columns": list(response_columns(config.kind)),
        "n_options": config.n_options if config.kind == "turing" else 1,
        "seed": config.seed,
        "delayed_strokes": config.delayed_strokes,
        "app_version": app_version,
        "ready": ready,
        "pilot": pilot,
        "pilot_copy": pilot_copy,
        "missing": missing,
        "completion": {
            "code": code,
            "redirect_url": url.replace("{code}", code) if url else None,
            "redirect_delay_ms": int(config.completion["redirect_delay_ms"]),
        },
        "save": {
            "download": bool(config.save["download"]) or pilot,
            "post_url": None if pilot else config.save["post_url"],
        },
    }


def readme(config: StudySettings, page: dict, pilot_folder: Path) -> str:
    """The build's README.md: its status, how to host it, the URL parameters, the responses."""
    if page["pilot"]:
        status = (
            "PILOT (stand-ins replace the missing human samples: try it, collect no data; "
            "its answers are marked pilot, never POSTed, and its completion code starts with "
            "PILOT-)"
        )
    elif page["ready"]:
        status = "ready to run"
    else:
        status = "NOT READY:\n\n" + "\n".join(f"- {m}" for m in page["missing"])
        status += (
            "\n\nTo try the pages before then: `prg-study build <study file> --pilot` builds a "
            "PILOT copy with stand-ins for the human samples (default folder "
            f"`{pilot_folder}/`; never for data)."
        )
    post = page["save"]["post_url"]
    if config.delayed_strokes:
        handwriting = (
            "delayed strokes (`delayed_strokes: true`): the robot dots its i's and j's and "
            "crosses its t's and f's after the word, and the capture page asks the writers to "
            "do the same."
        )
    else:
        handwriting = (
            "one stroke a word (`delayed_strokes: false`, as the paper): no dots or bars, "
            "for the robot and the writers."
        )
    saving = f"and POSTed (as text/plain) to {post}" if post else "(save.post_url also POSTs it)"
    return f"""# Study `{config.name}` ({config.kind}) — {status}

Open `index.html` (file:// works) or serve this folder from any static host
(`python -m http.server -d .` then http://127.0.0.1:8000/). On Prolific use the study URL
`https://HOST/PATH/index.html?PROLIFIC_PID={{{{%PROLIFIC_PID%}}}}&STUDY_ID={{{{%STUDY_ID%}}}}&SESSION_ID={{{{%SESSION_ID%}}}}`.

- Rows: `trials.json` holds {config.participants} counterbalanced rows. `?row=N` (1-based) picks
  row N; otherwise the row is `fnv1a32("{config.name}:" + PROLIFIC_PID) mod rows`
  (`studies.design.assign_row`), or random without a PROLIFIC_PID. For exact balance give
  each participant `?row=N` (a study per row, or a server that hands out rows in turn).
- Responses: one CSV row per trial, columns {", ".join(page["columns"])}; downloaded at the
  end {saving}.
- Completion code `{page["completion"]["code"]}`; redirect to {page["completion"]["redirect_url"]}.
- Ground truth: `trials.csv`, `stimuli.csv`. The capture page for human writers:
  `capture/index.html` (`?writer=ID`); its JSON files are human samples for
  `prg-study build --human DIR`.
- Handwriting: {handwriting}
"""
