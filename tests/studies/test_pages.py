"""Tests of ``studies.pages``: the page settings of a study and of its pilot, a script that stays
inside its HTML page, the pilot banner in the page, the README's status."""

from __future__ import annotations

import json
from pathlib import Path

from studies.pages import js_assignment, page_config, page_html, readme, response_columns
from tests.helpers.study_design import readability, turing

SAVE = {"download": False, "post_url": "https://example.org/save"}
COMPLETION = {"code": "ABC123", "url": "https://example.org/done?cc={code}"}


def test_a_pilot_never_passes_for_the_study():
    config = turing(save=SAVE, completion=COMPLETION)
    study = page_config(config, "1.0", True, [], pilot=False, pilot_copy=None)
    pilot = page_config(config, "1.0-pilot", True, [], pilot=True, pilot_copy="stand-ins")
    assert study["completion"]["code"] == "ABC123"
    assert study["completion"]["redirect_url"] == "https://example.org/done?cc=ABC123"
    assert study["save"] == {"download": False, "post_url": "https://example.org/save"}
    assert pilot["completion"]["code"] == "PILOT-ABC123"
    assert pilot["completion"]["redirect_url"] == "https://example.org/done?cc=PILOT-ABC123"
    assert pilot["save"] == {"download": True, "post_url": None}  # never POSTed
    assert study["columns"] == [*response_columns("turing")] and study["n_options"] == 5
    assert page_config(readability(), "1.0", True, [], False, None)["n_options"] == 1


def test_a_value_closing_its_script_tag_stays_inside_the_script():
    text = js_assignment("PRG_X", {"word": "</script><b>"})
    assert "</script>" not in text
    assert text.startswith("window.PRG_X = ") and text.endswith(";\n")
    assert json.loads(text[len("window.PRG_X = ") : -2]) == {"word": "</script><b>"}


def test_the_pilot_banner_is_on_the_page_and_escaped():
    plain = page_html("study").decode()
    pilot = page_html("study", banner="try <this> only").decode()
    assert "PILOT" not in plain
    assert "<title>PILOT \u2014 Handwriting study</title>" in pilot
    assert "try &lt;this&gt; only" in pilot and "<this>" not in pilot
    capture = page_html("capture").decode()
    assert "user-scalable=no" in capture and "trials.js" not in capture


def test_the_readme_says_what_is_missing_and_where_a_pilot_goes():
    config = turing()
    page = page_config(config, "1.0", False, ["word cat: 3 of 10 writers"], False, None)
    text = readme(config, page, Path("studies/t/pilot"))
    assert "NOT READY" in text and "- word cat: 3 of 10 writers" in text
    assert "`studies/t/pilot/`" in text
    ready = readme(config, page_config(config, "1.0", True, [], False, None), Path("p"))
    assert "ready to run" in ready and "NOT READY" not in ready
